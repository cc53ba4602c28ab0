//! Scene files (`[scene]`, named with `scene = ".."`): protocols that share one bench write it
//! once. A protocol standing in a scene compiles to exactly the task it would with the scene's
//! tables inline; mistakes in the protocol and in its scene come back in one pass, each in its
//! own file; a scene file checks alone and is no task; chains whose stages share a scene keep the
//! scene rule without a word.

use crate::common;

use std::path::Path;
use std::process::Command;

fn check(path: &str) -> compiler::Checked {
    compiler::check_file(Path::new(path), Some(Path::new("."))).unwrap()
}

/// The places of `checked`'s diagnostics: (code, file, line, col, covered text), sorted.
fn places(checked: &compiler::Checked) -> Vec<(String, String, usize, usize, String)> {
    let mut out: Vec<_> = checked
        .diagnostics
        .iter()
        .map(|d| {
            let (file, text) = checked.text_of(d).unwrap();
            let (line, col) = dsl::render::line_col(&text, d.span.start);
            let name = Path::new(&file)
                .file_name()
                .unwrap()
                .to_string_lossy()
                .to_string();
            (
                d.code.to_string(),
                name,
                line,
                col,
                text[d.span.start..d.span.end].to_string(),
            )
        })
        .collect();
    out.sort();
    out
}

#[test]
fn a_protocol_in_a_scene_file_compiles_to_the_task_with_the_scene_inline() {
    // The 5430's lid tasks share protocols/centrifuge_5430/scene.toml; written out inline, with
    // the lid's start where the scene left it, the task is the same but for its source.
    for (name, lid) in [("open_lid", "locked"), ("close_lid", "open")] {
        let path = format!("protocols/centrifuge_5430/{name}.toml");
        let shared = compiler::check_file(Path::new(&path), None).unwrap();
        assert!(shared.diagnostics.is_empty(), "{:#?}", shared.diagnostics);
        let scene = std::fs::read_to_string("protocols/centrifuge_5430/scene.toml").unwrap();
        let own = std::fs::read_to_string(&path).unwrap();
        let tables = &scene[scene.find("[robots.arm]").unwrap()..];
        let (head, rest) = own.split_once("[labware.centrifuge]").unwrap();
        let (_, rest) = rest.split_once("[[steps]]").unwrap();
        let inline = format!(
            "{}{}\n{}\n[[steps]]{rest}",
            head.replace("scene = \"scene.toml\"\n", ""),
            tables.replace(
                "pose = { pos_m = [-0.1, 0.0, 0.824], yaw_deg = 90 }",
                &format!(
                    "pose = {{ pos_m = [-0.1, 0.0, 0.824], yaw_deg = 90 }}\nstate = {{ lid = \"{lid}\" }}"
                )
            ),
            "",
        );
        let (task, diags) = compiler::compile_source(&inline, &path);
        let mut task = task.unwrap_or_else(|| panic!("{inline}\n{diags:#?}"));
        let mut expected = shared.task.unwrap();
        task.source.clear();
        expected.source.clear();
        for s in task.stages.iter_mut().chain(expected.stages.iter_mut()) {
            s.source.clear();
        }
        assert_eq!(task, expected, "{name}");
    }
}

#[test]
fn mistakes_in_a_protocol_and_its_scene_come_back_in_one_pass() {
    let checked = check("tests/corpus/faulty/scene_mistakes.toml");
    assert!(checked.task.is_none());
    assert_eq!(
        places(&checked),
        [
            (
                "E0010".to_string(),
                "cycler_scene_misspelt.toml".to_string(),
                12,
                8,
                "\"thermal_cycle\"".to_string()
            ),
            (
                "E0012".into(),
                "scene_mistakes.toml".into(),
                17,
                6,
                "\"close_lids\"".into()
            ),
            (
                "E0020".into(),
                "scene_mistakes.toml".into(),
                11,
                14,
                "\"31.5 sec\"".into()
            ),
        ]
    );
    // The scene's own diagnostic says which protocol named it, and where.
    let d = checked
        .diagnostics
        .iter()
        .find(|d| d.code == dsl::Code::E0010)
        .unwrap();
    assert!(
        d.notes
            .iter()
            .any(|n| n.starts_with("scene of ") && n.ends_with("scene_mistakes.toml:5:9")),
        "{:?}",
        d.notes
    );
}

#[test]
fn a_scene_file_checks_alone_and_is_no_task() {
    let ok = check("protocols/centrifuge_5430/scene.toml");
    assert!(
        ok.diagnostics.is_empty() && ok.task.is_none(),
        "{:#?}",
        ok.diagnostics
    );
    let bad = check("tests/corpus/faulty/stages/cycler_scene_misspelt.toml");
    assert_eq!(
        places(&bad),
        [(
            "E0010".to_string(),
            "cycler_scene_misspelt.toml".to_string(),
            12,
            8,
            "\"thermal_cycle\"".to_string()
        )]
    );
    let run = |args: &[&str]| {
        Command::new(env!("CARGO_BIN_EXE_autobio"))
            .args(args)
            .output()
            .unwrap()
    };
    let checked = run(&["check", "protocols/centrifuge_5430/scene.toml"]);
    assert!(checked.status.success());
    let compiled = run(&["compile", "protocols/centrifuge_5430/scene.toml"]);
    assert_eq!(compiled.status.code(), Some(2));
    assert!(
        String::from_utf8_lossy(&compiled.stderr).contains("is a scene file, not a task"),
        "{}",
        String::from_utf8_lossy(&compiled.stderr)
    );
    // Not listed among the shipped tasks.
    assert!(
        !common::shipped_protocols()
            .iter()
            .any(|p| p.ends_with("centrifuge_5430/scene.toml"))
    );
}

#[test]
fn the_scene_file_places_the_camera_once() {
    let dir = common::scratch("scene-camera");
    std::fs::write(
        dir.join("scene.toml"),
        "format = 1\n[scene]\n[robots.arm]\nmodel = \"ur5e_2f85\"\nbase = { pos_m = [0.0, 0.5, 0.824] }\n\
         [labware.cycler]\nkind = \"thermal_cycler\"\npose = { pos_m = [-0.05, 0.0, 0.824], yaw_deg = -90 }\n\
         [camera]\npos_m = [1.0, -1.0, 1.6]\nlook_at_m = [0.0, 0.0, 0.9]\n",
    )
    .unwrap();
    let protocol = dir.join("close.toml");
    std::fs::write(
        &protocol,
        "format = 1\nscene = \"scene.toml\"\n[protocol]\nid = \"t.close\"\ninstruction = \"close it\"\n\
         time_limit = \"30 s\"\n[labware.cycler]\nstate = { lid = \"open\" }\n\
         [camera]\npos_m = [1.0, 1.0, 1.6]\nlook_at_m = [0.0, 0.0, 0.9]\n\
         [[steps]]\ndo = \"close_lid\"\non = \"cycler\"\nwith = \"arm\"\n[success]\nall = [\"cycler.lid is locked\"]\n",
    )
    .unwrap();
    let checked = compiler::check_file(&protocol, None).unwrap();
    let codes: Vec<_> = places(&checked)
        .into_iter()
        .map(|p| (p.0, p.1, p.2))
        .collect();
    assert_eq!(codes, [("E0015".to_string(), "close.toml".to_string(), 9)]);
    // Without its own camera, the protocol is filmed from the scene's.
    let text = std::fs::read_to_string(&protocol).unwrap();
    let own = text.replace(
        "[camera]\npos_m = [1.0, 1.0, 1.6]\nlook_at_m = [0.0, 0.0, 0.9]\n",
        "",
    );
    std::fs::write(&protocol, own).unwrap();
    let checked = compiler::check_file(&protocol, None).unwrap();
    let task = checked
        .task
        .unwrap_or_else(|| panic!("{:#?}", checked.diagnostics));
    let fixed = serde_json::to_value(&task.cameras).unwrap().to_string();
    assert!(fixed.contains("1.6"), "{fixed}");
}

/// Stages that share a scene file each check it; its mistakes are said once, naming every
/// protocol that used it. A scene file named as a stage is refused as what it is.
#[test]
fn a_chain_whose_stages_share_a_scene_says_its_mistakes_once() {
    let dir = common::scratch("scene-chain");
    std::fs::write(
        dir.join("scene.toml"),
        "format = 1\n[scene]\n[robots.arm]\nmodel = \"ur5e_2f85\"\nbase = { pos_m = [0.0, 0.5, 0.824] }\n\
         [labware.cycler]\nkind = \"thermal_cycler\"\npose = { pos_m = [-0.05, 0.0, 0.824], yaw_deg = -90 }\n\
         [randomise.cycler]\nxy_m = 2\n",
    )
    .unwrap();
    for (name, lid, action, goal) in [
        ("open", "locked", "open_lid", "open"),
        ("close", "open", "close_lid", "locked"),
    ] {
        std::fs::write(
            dir.join(format!("{name}.toml")),
            format!(
                "format = 1\nscene = \"scene.toml\"\n[protocol]\nid = \"t.{name}\"\ninstruction = \"{name} it\"\n\
                 time_limit = \"30 s\"\n[labware.cycler]\nstate = {{ lid = \"{lid}\" }}\n\
                 [[steps]]\ndo = \"{action}\"\non = \"cycler\"\nwith = \"arm\"\n[success]\nall = [\"cycler.lid is {goal}\"]\n"
            ),
        )
        .unwrap();
    }
    let chain = dir.join("chain.toml");
    std::fs::write(
        &chain,
        "format = 1\n[chain]\nid = \"t.chain\"\n[[stages]]\nprotocol = \"open.toml\"\n[[stages]]\nprotocol = \"close.toml\"\n",
    )
    .unwrap();
    let checked = compiler::check_file(&chain, None).unwrap();
    assert!(checked.task.is_some(), "{:#?}", checked.diagnostics);
    let said: Vec<_> = places(&checked);
    assert_eq!(
        said,
        [(
            "W0003".to_string(),
            "scene.toml".to_string(),
            10,
            8,
            "2".to_string()
        )],
        "{:#?}",
        checked.diagnostics
    );
    let notes = &checked.diagnostics[0].notes;
    for named in ["open.toml", "close.toml"] {
        assert!(
            notes
                .iter()
                .any(|n| n.starts_with("scene of ") && n.contains(&format!("{named}, named at"))),
            "{notes:?}"
        );
    }
    std::fs::write(
        &chain,
        "format = 1\n[chain]\nid = \"t.chain\"\n[[stages]]\nprotocol = \"open.toml\"\n[[stages]]\nprotocol = \"scene.toml\"\n",
    )
    .unwrap();
    let refused = compiler::check_file(&chain, None).unwrap();
    let d = refused
        .diagnostics
        .iter()
        .find(|d| d.code == dsl::Code::E0006)
        .unwrap_or_else(|| panic!("{:#?}", refused.diagnostics));
    assert!(d.message.contains("is a scene file"), "{}", d.message);
}
