//! The terminal's [`Progress`]: notices as `gloffuse: …` lines on stderr, and a progress
//! bar on stderr while a task runs (indicatif draws it only when stderr is a terminal).

use indicatif::{ProgressBar, ProgressStyle};
use std::io::Write as _;
use std::sync::Mutex;
use std::time::Duration;

use gloffuse::progress::Progress;

#[derive(Default)]
pub struct Terminal {
    bar: Mutex<Option<ProgressBar>>,
}

impl Terminal {
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
        let bar = ProgressBar::new(steps);
        bar.set_style(
            ProgressStyle::with_template(
                "{spinner} {msg} [{bar:30}] {pos}/{len}, {elapsed} (ETA {eta})",
            )
            .expect("a valid template")
            .progress_chars("=> "),
        );
        bar.set_message(message.to_string());
        bar.enable_steady_tick(Duration::from_millis(200));
        if let Ok(mut guard) = self.bar.lock()
            && let Some(old) = guard.replace(bar)
        {
            old.finish_and_clear();
        }
    }

    fn set(&self, done: u64) {
        self.with_bar(|bar| bar.set_position(done));
    }

    fn step(&self) {
        self.with_bar(|bar| bar.inc(1));
    }

    fn end(&self) {
        if let Ok(mut guard) = self.bar.lock()
            && let Some(bar) = guard.take()
        {
            bar.finish_and_clear();
        }
    }
}

/// A line on stderr; a closed stderr is not worth failing over.
pub fn eprintln_quietly(line: &str) {
    let _ = writeln!(std::io::stderr(), "{line}");
}
