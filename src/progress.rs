//! Progress on stderr, for evaluations and dataset generation: on a terminal, one bar redrawn in
//! place (items done, a running figure, ETA) with failures printed above it; otherwise one plain
//! line per item, for logs and CI.

use scoring::eval::Progress;
use std::io::IsTerminal;
use std::time::Instant;

pub(crate) struct ProgressView {
    label: String,
    /// The task evaluated, so that a failure line names what its seed drew.
    task: Option<compiler::Task>,
    bar: bool,
    started: Instant,
    drawn: bool,
    /// Dataset episodes left out so far.
    left_out: usize,
}

impl ProgressView {
    pub(crate) fn new(label: &str) -> ProgressView {
        ProgressView {
            label: label.to_string(),
            task: None,
            bar: std::io::stderr().is_terminal(),
            started: Instant::now(),
            drawn: false,
            left_out: 0,
        }
    }

    /// Progress of an evaluation of `task`: each failure line also names the parameters its
    /// seed drew.
    pub(crate) fn for_task(task: &compiler::Task) -> ProgressView {
        ProgressView {
            task: Some(task.clone()),
            ..ProgressView::new(&task.id)
        }
    }

    /// `; drew row=B, col=4` for a seed of a task with parameters, else nothing.
    fn drawn(&self, seed: u64) -> String {
        let Some(task) = self.task.as_ref().filter(|t| !t.params.is_empty()) else {
            return String::new();
        };
        let params = task.sample(seed).params;
        let values: Vec<String> = params.iter().map(|(k, v)| format!("{k}={v}")).collect();
        format!("; drew {}", values.join(", "))
    }

    /// One evaluated episode.
    pub(crate) fn update(&mut self, p: &Progress) {
        let e = p.result;
        let rate = 100.0 * p.successes as f64 / p.done.max(1) as f64;
        let outcome = serde_json::to_value(e.outcome)
            .ok()
            .and_then(|v| v.as_str().map(str::to_string))
            .unwrap_or_default();
        let reason = match e.error.as_deref() {
            Some(r) => format!(": {r}"),
            None if !e.success => failed_checks(&e.verdict),
            None => String::new(),
        };
        let drawn = if e.success {
            String::new()
        } else {
            self.drawn(e.seed)
        };
        self.draw(
            (p.done, p.total, p.resumed),
            &format!("success {rate:.1}%"),
            e.error
                .as_ref()
                .map(|_| format!("seed {} (run {}{drawn}): {outcome}{reason}", e.seed, e.run)),
            &format!(
                "{}/{} seed {} (run {}{drawn}): {outcome}{reason}  running success {rate:.1}%",
                p.done, p.total, e.seed, e.run
            ),
        );
    }

    /// One episode written to a dataset, or left out.
    pub(crate) fn step(&mut self, s: &demos::Step<'_>) {
        self.left_out += usize::from(s.result.is_err());
        let what = match s.result {
            Ok(frames) => format!("{frames} frames"),
            Err(why) => format!("not written: {why}"),
        };
        self.draw(
            (s.done, s.total, 0),
            &format!("{} left out", self.left_out),
            s.result
                .err()
                .map(|_| format!("{} seed {}: {what}", s.task, s.seed)),
            &format!("{}/{} {} seed {}: {what}", s.done, s.total, s.task, s.seed),
        );
    }

    /// `count`: (done, total, done before this run); `figure` follows the bar; `failure` is
    /// printed above it; `plain` is the line when stderr is not a terminal.
    fn draw(
        &mut self,
        (done, total, resumed): (usize, usize, usize),
        figure: &str,
        failure: Option<String>,
        plain: &str,
    ) {
        if !self.bar {
            errln!("  {plain}");
            return;
        }
        if let Some(line) = failure {
            err!("\r\x1b[K");
            errln!("  {line}");
        }
        let ran = done - resumed.min(done);
        let left = total.saturating_sub(done);
        let eta = if ran > 0 {
            let s = self.started.elapsed().as_secs_f64() / ran as f64 * left as f64;
            format!("{}:{:02}", (s / 60.0) as u64, s as u64 % 60)
        } else {
            "?".into()
        };
        const WIDTH: usize = 24;
        let filled = WIDTH * done.min(total) / total.max(1);
        err!(
            "\r\x1b[K  {} [{}{}] {done}/{total}  {figure}  ETA {eta}",
            self.label,
            "#".repeat(filled),
            ".".repeat(WIDTH - filled),
        );
        self.drawn = true;
    }

    /// Ends the bar's line.
    pub(crate) fn finish(&mut self) {
        if self.bar && self.drawn {
            errln!("");
        }
    }
}

/// `: \`tube in target.B3\` failed (height 31.0 mm, within 5.0 mm)`: each check that did not
/// hold at the end, with the parts that failed and by how much, in the author's units.
fn failed_checks(v: &results::verdict::Verdict) -> String {
    let failed: Vec<String> = v
        .predicates()
        .iter()
        .filter(|p| !p.holds)
        .map(|p| {
            let parts: Vec<String> = p
                .parts
                .iter()
                .filter(|q| !q.holds)
                .map(|q| {
                    let (value, tolerance, unit) = match q.unit.as_str() {
                        "m" => (q.value * 1e3, q.tolerance * 1e3, "mm"),
                        "rad" => (q.value.to_degrees(), q.tolerance.to_degrees(), "°"),
                        u => (q.value, q.tolerance, u),
                    };
                    format!("{} {value:.1} {unit}, within {tolerance:.1} {unit}", q.name)
                })
                .collect();
            if parts.is_empty() {
                format!("`{}` failed", p.text)
            } else {
                format!("`{}` failed ({})", p.text, parts.join("; "))
            }
        })
        .collect();
    if failed.is_empty() {
        String::new()
    } else {
        format!(": {}", failed.join(", "))
    }
}
