//! Progress of an evaluation on stderr: on a terminal, one bar redrawn in place (episodes done,
//! running success rate, ETA) with failures printed above it; otherwise one plain line per
//! episode, for logs and CI.

use scoring::eval::Progress;
use std::io::IsTerminal;
use std::time::Instant;

pub struct ProgressView {
    label: String,
    bar: bool,
    started: Instant,
    drawn: bool,
}

impl ProgressView {
    pub fn new(label: &str) -> ProgressView {
        ProgressView {
            label: label.to_string(),
            bar: std::io::stderr().is_terminal(),
            started: Instant::now(),
            drawn: false,
        }
    }

    pub fn update(&mut self, p: &Progress) {
        let e = p.result;
        let rate = 100.0 * p.successes as f64 / p.done.max(1) as f64;
        let outcome = serde_json::to_value(e.outcome)
            .ok()
            .and_then(|v| v.as_str().map(str::to_string))
            .unwrap_or_default();
        if !self.bar {
            errln!(
                "  {}/{} seed {} (run {}): {outcome}{}  running success {rate:.1}%",
                p.done,
                p.total,
                e.seed,
                e.run,
                e.error
                    .as_deref()
                    .map(|r| format!(": {r}"))
                    .unwrap_or_default(),
            );
            return;
        }
        if let Some(reason) = &e.error {
            err!("\r\x1b[K");
            errln!("  seed {} (run {}): {outcome}: {reason}", e.seed, e.run);
        }
        let ran = p.done - p.resumed;
        let left = p.total - p.done;
        let eta = if ran > 0 {
            let s = self.started.elapsed().as_secs_f64() / ran as f64 * left as f64;
            format!("{}:{:02}", (s / 60.0) as u64, s as u64 % 60)
        } else {
            "?".into()
        };
        const WIDTH: usize = 24;
        let filled = WIDTH * p.done / p.total.max(1);
        err!(
            "\r\x1b[K  {} [{}{}] {}/{}  success {rate:.1}%  ETA {eta}",
            self.label,
            "#".repeat(filled),
            ".".repeat(WIDTH - filled),
            p.done,
            p.total,
        );
        self.drawn = true;
    }

    /// Ends the bar's line.
    pub fn finish(&mut self) {
        if self.bar && self.drawn {
            errln!("");
        }
    }
}
