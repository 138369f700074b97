//! How long-running library calls say what they are doing: they call a [`Progress`], and the
//! caller decides what to show (the CLI draws on stderr; tests and scripts pass [`Quiet`]).
//! The library itself never prints.

/// Receives notices and the progress of one task at a time. Every method has a do-nothing
/// default; `step` may be called from worker threads.
pub trait Progress: Sync {
    /// A one-line notice for the user (which Blender is used, that bpy is being installed).
    fn notice(&self, _message: &str) {}
    /// A notice that tells the user which input to change: the CLI names the flags.
    fn advise(&self, hint: &crate::Hint) {
        self.notice(&hint.to_string());
    }
    /// A task of `steps` steps starts; `message` says what it does.
    fn begin(&self, _message: &str, _steps: u64) {}
    /// `done` steps of the current task are finished.
    fn set(&self, _done: u64) {}
    /// One more step of the current task is finished.
    fn step(&self) {}
    /// What the current task is doing now, in place of the message it began with.
    fn doing(&self, _what: &str) {}
    /// A task whose length is known only as it runs (a render: Cycles estimates it) starts;
    /// `estimate` follows it instead of `set` or `step`.
    fn begin_estimated(&self, _message: &str) {}
    /// The estimated task is `done` (0 to 1) finished and needs about `seconds_left` more
    /// (none: no estimate yet).
    fn estimate(&self, _done: f64, _seconds_left: Option<f64>) {}
    /// The current task is over (finished or failed).
    fn end(&self) {}
}

/// A [`Progress`] that shows nothing.
pub struct Quiet;

impl Progress for Quiet {}
