fn main() {
    let file = std::env::args().nth(1).unwrap_or("protocols/thermal_cycler/close_lid.toml".into());
    let n: usize = std::env::args().nth(2).map(|s| s.parse().unwrap()).unwrap_or(5);
    let src = std::fs::read_to_string(&file).unwrap();
    let (task, d) = compiler::compile_source(&src, &file);
    let task = task.unwrap_or_else(|| panic!("{d:?}"));
    let opts = scoring::eval::EvalOptions { episodes: n, seed: 0, out: None, record: false, image_every: 0 };
    let r = scoring::evaluate(&task, &opts, |e| println!("seed {} success {} t {:.2} err {:?} {:?}", e.seed, e.success, e.sim_time_s, e.error, e.verdict.predicates.iter().map(|p| (p.value, p.holds)).collect::<Vec<_>>())).unwrap();
    println!("{:?}", r.summary);
}
