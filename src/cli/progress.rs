//! The terminal's [`Progress`]: notices as `gloffuse: …` lines on stderr, and a progress
//! bar on stderr while a task runs (indicatif draws it only when stderr is a terminal).

use indicatif::{ProgressBar, ProgressStyle};
use std::io::Write as _;
use std::sync::Mutex;
use std::time::Duration;

use gloffuse::progress::Progress;
use gloffuse::report::escape::{terminal, terminal_lines};

#[derive(Default)]
pub struct Terminal {
    bar: Mutex<Option<ProgressBar>>,
}

/// The resolution of a bar that follows an estimate.
const ESTIMATE_STEPS: u64 = 1000;

impl Terminal {
    /// Shows `bar` (drawn with `template`) in place of the one before.
    fn start(&self, bar: ProgressBar, template: &str, message: &str) {
        bar.set_style(
            ProgressStyle::with_template(template)
                .expect("a valid template")
                .progress_chars("=> "),
        );
        bar.set_message(terminal(message).into_owned());
        bar.enable_steady_tick(Duration::from_millis(200));
        if let Ok(mut guard) = self.bar.lock()
            && let Some(old) = guard.replace(bar)
        {
            old.finish_and_clear();
        }
    }

    fn with_bar(&self, f: impl FnOnce(&ProgressBar)) {
        if let Ok(guard) = self.bar.lock()
            && let Some(bar) = guard.as_ref()
        {
            f(bar);
        }
    }
}

impl Progress for Terminal {
    fn advise(&self, hint: &gloffuse::Hint) {
        self.notice(&hint.render(super::args::flag));
    }

    fn notice(&self, message: &str) {
        let line = format!("gloffuse: {message}");
        match self.bar.lock().ok().and_then(|g| g.clone()) {
            Some(bar) => bar.suspend(|| eprintln_quietly(&line)),
            None => eprintln_quietly(&line),
        }
    }

    fn begin(&self, message: &str, steps: u64) {
        self.start(
            ProgressBar::new(steps),
            "{spinner} {msg} [{bar:30}] {pos}/{len}, {elapsed} (ETA {eta})",
            message,
        );
    }

    fn begin_estimated(&self, message: &str) {
        let bar = ProgressBar::new(ESTIMATE_STEPS);
        bar.set_prefix(seconds_left_words(None));
        self.start(
            bar,
            "{spinner} {msg} [{bar:30}] {elapsed} ({prefix})",
            message,
        );
    }

    fn estimate(&self, done: f64, seconds_left: Option<f64>) {
        self.with_bar(|bar| {
            bar.set_position((done.clamp(0.0, 1.0) * ESTIMATE_STEPS as f64).round() as u64);
            bar.set_prefix(seconds_left_words(seconds_left));
        });
    }

    fn set(&self, done: u64) {
        self.with_bar(|bar| bar.set_position(done));
    }

    fn step(&self) {
        self.with_bar(|bar| bar.inc(1));
    }

    fn doing(&self, what: &str) {
        self.with_bar(|bar| bar.set_message(terminal(what).into_owned()));
    }

    fn end(&self) {
        if let Ok(mut guard) = self.bar.lock()
            && let Some(bar) = guard.take()
        {
            bar.finish_and_clear();
        }
    }
}

/// What an estimated task still needs, in words: Cycles' estimate, or that it has none yet
/// or has run out.
fn seconds_left_words(seconds_left: Option<f64>) -> String {
    match seconds_left {
        None => "waiting for Cycles' first estimate".to_string(),
        Some(s) if s < 0.5 => "finishing: past Cycles' estimate".to_string(),
        Some(s) if s < 90.0 => format!("about {s:.0} s left, by Cycles' estimate"),
        Some(s) => {
            let whole = s.round() as u64;
            format!(
                "about {} min {:02} s left, by Cycles' estimate",
                whole / 60,
                whole % 60
            )
        }
    }
}

/// A line on stderr (or several: its newlines are kept), with every other control
/// character shown as text, since it may quote names from users' files; a closed stderr is
/// not worth failing over.
pub fn eprintln_quietly(line: &str) {
    let _ = writeln!(std::io::stderr(), "{}", terminal_lines(line));
}

#[cfg(test)]
mod tests {
    use super::seconds_left_words;

    #[test]
    fn the_time_left_reads_as_minutes_and_seconds() {
        assert_eq!(
            seconds_left_words(Some(37.44)),
            "about 37 s left, by Cycles' estimate"
        );
        assert_eq!(
            seconds_left_words(Some(119.6)),
            "about 2 min 00 s left, by Cycles' estimate"
        );
        assert_eq!(
            seconds_left_words(Some(0.2)),
            "finishing: past Cycles' estimate"
        );
        assert!(seconds_left_words(None).contains("waiting"));
    }
}
