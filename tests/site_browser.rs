//! The leaderboard site in a real browser: headless Chromium (Debian's package, installed by
//! `make setup`) opens the built pages from files, driven over the DevTools protocol. Every
//! request a page makes must be a local file (no network, none failing), the rendered tables must
//! hold the submitted numbers, and a screenshot of the ranking page and of a task page is taken
//! (left under the test's scratch folder for a human to look at).

use crate::common;

use common::scratch;
use serde_json::{Value, json};
use std::io::{BufRead, BufReader};
use std::net::TcpStream;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};
use tungstenite::{Message, WebSocket};

/// A site built from one verified expert bundle of a 2-episode suite.
fn site(dir: &Path) -> PathBuf {
    let suites = dir.join("suites");
    std::fs::create_dir_all(&suites).unwrap();
    let protocol =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("protocols/thermal_cycler/close_lid.toml");
    std::fs::write(
        suites.join("mini.toml"),
        format!(
            "format = 1\n[suite]\nname = \"mini\"\nepisodes = 2\nseed = 0\nruns = 1\ntasks = [{:?}]\n",
            protocol.display().to_string()
        ),
    )
    .unwrap();
    let run = dir.join("run");
    common::eval_suite(&suites.join("mini.toml"), &run, &[]);
    let bundles = dir.join("bundles");
    std::fs::create_dir_all(&bundles).unwrap();
    let bundle = bundles.join("expert.tar.zst");
    common::submit(&run, "scripted expert", &bundle, &[]);
    common::autobio_ok(&[
        "leaderboard",
        "verify",
        bundle.to_str().unwrap(),
        "--suites",
        suites.to_str().unwrap(),
    ]);
    let site = dir.join("site");
    common::autobio_ok(&[
        "leaderboard",
        "build",
        bundles.to_str().unwrap(),
        "--out",
        site.to_str().unwrap(),
    ]);
    site
}

/// Headless Chromium with its DevTools endpoint; killed when dropped.
struct Browser {
    child: Child,
    ws: WebSocket<TcpStream>,
    next_id: u64,
    session: String,
}

impl Drop for Browser {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

impl Browser {
    fn start(profile: &Path) -> Browser {
        let mut child = Command::new("chromium")
            .args([
                "--headless=new",
                "--no-sandbox",
                "--disable-gpu",
                "--no-first-run",
                "--disable-background-networking",
                "--remote-debugging-port=0",
                "--window-size=1280,900",
                &format!("--user-data-dir={}", profile.display()),
                "about:blank",
            ])
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .expect("chromium runs (make setup installs it)");
        let (tx, rx) = std::sync::mpsc::channel();
        let stderr = child.stderr.take().unwrap();
        std::thread::spawn(move || {
            for line in BufReader::new(stderr).lines().map_while(Result::ok) {
                if let Some(url) = line.strip_prefix("DevTools listening on ") {
                    let _ = tx.send(url.to_string());
                }
            }
        });
        let url = rx
            .recv_timeout(Duration::from_secs(60))
            .expect("chromium's DevTools endpoint within 60 s");
        let host = url
            .trim_start_matches("ws://")
            .split('/')
            .next()
            .unwrap()
            .to_string();
        let stream = TcpStream::connect(&host).unwrap();
        stream
            .set_read_timeout(Some(Duration::from_secs(30)))
            .unwrap();
        let (ws, _) = tungstenite::client(url.as_str(), stream).unwrap();
        let mut b = Browser {
            child,
            ws,
            next_id: 0,
            session: String::new(),
        };
        let target = b.call("Target.createTarget", json!({"url": "about:blank"}), false);
        let attached = b.call(
            "Target.attachToTarget",
            json!({"targetId": target["targetId"], "flatten": true}),
            false,
        );
        b.session = attached["sessionId"].as_str().unwrap().to_string();
        b.call("Network.enable", json!({}), true);
        b.call("Page.enable", json!({}), true);
        b
    }

    fn send(&mut self, method: &str, params: Value, in_page: bool) -> u64 {
        self.next_id += 1;
        let mut msg = json!({"id": self.next_id, "method": method, "params": params});
        if in_page {
            msg["sessionId"] = self.session.clone().into();
        }
        self.ws.send(Message::text(msg.to_string())).unwrap();
        self.next_id
    }

    fn read(&mut self) -> Value {
        loop {
            if let Message::Text(t) = self.ws.read().expect("a DevTools message within 30 s") {
                return serde_json::from_str(&t).unwrap();
            }
        }
    }

    /// Sends a command and returns its result (events in between are dropped).
    fn call(&mut self, method: &str, params: Value, in_page: bool) -> Value {
        let id = self.send(method, params, in_page);
        loop {
            let m = self.read();
            if m["id"] == id {
                assert!(m.get("error").is_none(), "{method}: {m}");
                return m["result"].clone();
            }
        }
    }

    /// Opens `url` and waits for its load event; every request it made and every failed one.
    fn open(&mut self, url: &str) -> (Vec<String>, Vec<String>) {
        self.send("Page.navigate", json!({"url": url}), true);
        let (mut requested, mut failed) = (Vec::new(), Vec::new());
        let deadline = Instant::now() + Duration::from_secs(30);
        loop {
            assert!(Instant::now() < deadline, "{url} did not load in 30 s");
            let m = self.read();
            match m["method"].as_str() {
                Some("Network.requestWillBeSent") => requested.push(
                    m["params"]["request"]["url"]
                        .as_str()
                        .unwrap_or_default()
                        .to_string(),
                ),
                Some("Network.loadingFailed") => failed.push(m["params"].to_string()),
                Some("Page.loadEventFired") => break,
                _ => {}
            }
        }
        (requested, failed)
    }

    fn eval(&mut self, expression: &str) -> Value {
        self.call(
            "Runtime.evaluate",
            json!({"expression": expression, "returnByValue": true}),
            true,
        )["result"]["value"]
            .clone()
    }

    fn screenshot(&mut self, path: &Path) -> usize {
        use base64::Engine;
        let r = self.call("Page.captureScreenshot", json!({"format": "png"}), true);
        let png = base64::engine::general_purpose::STANDARD
            .decode(r["data"].as_str().unwrap())
            .unwrap();
        assert_eq!(&png[..8], b"\x89PNG\r\n\x1a\n");
        std::fs::write(path, &png).unwrap();
        png.len()
    }
}

#[test]
fn the_site_loads_from_files_with_no_network_and_shows_the_submitted_numbers() {
    let dir = scratch("site-browser");
    let site = site(&dir);
    let mut browser = Browser::start(&dir.join("profile"));
    for (page, shot) in [
        ("index.html", "ranking.png"),
        ("tasks/thermal-cycler-close-lid.html", "task.png"),
    ] {
        let path = std::fs::canonicalize(site.join(page)).unwrap();
        let url = format!("file://{}", path.display());
        let (requested, failed) = browser.open(&url);
        assert!(requested.iter().any(|r| r == &url), "{requested:?}");
        let elsewhere: Vec<&String> = requested
            .iter()
            .filter(|r| !r.starts_with("file://") && !r.starts_with("data:"))
            .collect();
        assert!(
            elsewhere.is_empty(),
            "{page} asked the network for {elsewhere:?}"
        );
        assert!(failed.is_empty(), "{page}: failed requests {failed:?}");
        let bytes = browser.screenshot(&dir.join(shot));
        assert!(bytes > 10_000, "{page}: a {bytes}-byte screenshot");
        let tables: String = browser
            .eval("[...document.querySelectorAll('table')].map(t => t.innerText).join('\\n')")
            .as_str()
            .unwrap()
            .to_string();
        let svg = browser
            .eval("document.querySelectorAll('svg').length")
            .as_u64()
            .unwrap();
        assert!(svg >= 1, "{page}: no chart drawn");
        if page == "index.html" {
            // The ranking row: rank, model, training, observation, standing, 100.0% success;
            // the paper's pi0 row.
            let row = tables
                .lines()
                .find(|l| l.contains("scripted expert"))
                .unwrap_or_else(|| panic!("{tables}"));
            let cells: Vec<&str> = row.split('\t').map(str::trim).collect();
            assert_eq!(
                cells[..6],
                ["1", "scripted expert", "", "scripted", "verified", "100.0"],
                "{row}"
            );
            assert!(tables.contains("99.7 ± 0.3"), "the paper's row: {tables}");
        } else {
            let row = tables
                .lines()
                .find(|l| l.starts_with("scripted expert"))
                .unwrap_or_else(|| panic!("{tables}"));
            assert!(row.contains("100.0\t[34.2, 100.0]\t1.000"), "{row}");
        }
    }
}
