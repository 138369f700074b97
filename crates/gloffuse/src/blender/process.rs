//! Process spawning: a child in its own process group with its output in a file, a
//! timeout that kills the whole group, and shell quoting for the commands gloffuse prints.

use std::ffi::{OsStr, OsString};
use std::fs::File;
use std::io;
use std::os::unix::process::{CommandExt, ExitStatusExt};
use std::process::{Command, ExitStatus, Stdio};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::time::{Duration, Instant};

/// A way to stop Blender from outside: the caller keeps a clone (the CLI's Ctrl-C handler
/// does) and passes one in with the options of every call that runs Blender. Clones share
/// one state.
#[derive(Clone, Debug, Default)]
pub struct Cancel(Arc<CancelState>);

#[derive(Debug, Default)]
struct CancelState {
    requested: AtomicBool,
    /// How many [`run_logged`] calls are waiting for a child, and [`Hold`]s are alive,
    /// right now: each will notice a request.
    listening: AtomicUsize,
}

impl Cancel {
    /// Asks every child being waited for to be stopped: their waits kill the process group
    /// and return [`Exit::Interrupted`], and so does every later run, and every [`Cancel::check`].
    /// False when nothing listens (no child waited for, no [`Hold`]: the caller may then end
    /// at once). Only atomics: safe in a signal handler.
    pub fn request(&self) -> bool {
        self.0.requested.store(true, Ordering::SeqCst);
        self.0.listening.load(Ordering::SeqCst) > 0
    }

    pub fn is_requested(&self) -> bool {
        self.0.requested.load(Ordering::SeqCst)
    }

    /// Makes a request wait for the holder's next [`Cancel::check`] while the guard lives:
    /// held around work that has temporary files beside a user's (or already replaced some),
    /// so a stop removes them and says what was written instead of ending the process there.
    pub fn hold(&self) -> Hold {
        self.0.listening.fetch_add(1, Ordering::SeqCst);
        Hold(self.clone())
    }

    /// `Err(Interrupted)` once a stop was requested: called between steps of held work.
    pub fn check(&self) -> Result<(), crate::Error> {
        if self.is_requested() {
            return Err(crate::Error::Interrupted {
                log: None,
                written: Vec::new(),
            });
        }
        Ok(())
    }
}

/// See [`Cancel::hold`].
#[derive(Debug)]
pub struct Hold(Cancel);

impl Drop for Hold {
    fn drop(&mut self) {
        self.0.0.listening.fetch_sub(1, Ordering::SeqCst);
    }
}

/// Two handles are equal when they are clones of one another.
impl PartialEq for Cancel {
    fn eq(&self, other: &Self) -> bool {
        Arc::ptr_eq(&self.0, &other.0)
    }
}

/// Counts a wait for [`Cancel::request`] while it lasts.
struct Waiting<'a>(&'a Cancel);

impl<'a> Waiting<'a> {
    fn new(cancel: &'a Cancel) -> Self {
        cancel.0.listening.fetch_add(1, Ordering::SeqCst);
        Waiting(cancel)
    }
}

impl Drop for Waiting<'_> {
    fn drop(&mut self) {
        self.0.0.listening.fetch_sub(1, Ordering::SeqCst);
    }
}

/// How a child ended.
#[derive(Debug)]
pub enum Exit {
    Finished(ExitStatus),
    /// The timeout passed; the child's process group was killed and the child reaped.
    TimedOut,
    /// [`Cancel::request`] was called; the child's process group was killed and the child
    /// reaped.
    Interrupted,
}

/// Kills `child`'s whole process group (its id is the child's pid: `process_group(0)`)
/// and reaps it.
fn kill_group(child: &mut std::process::Child) -> io::Result<()> {
    // The child is not yet reaped, so its id cannot have been reused.
    let killed = match libc::pid_t::try_from(child.id()) {
        // SAFETY: killpg only sends a signal; it touches no memory of ours.
        Ok(pgid) => (unsafe { libc::killpg(pgid, libc::SIGKILL) }) == 0,
        Err(_) => false,
    };
    if !killed {
        let _ = child.kill();
    }
    child.wait()?;
    Ok(())
}

/// Runs `argv` in a process group of its own, stdin from /dev/null, stdout and stderr both
/// to `out`, and waits at most `timeout`. On timeout, or when `cancel` is requested, the
/// whole group is killed (SIGKILL) and the child reaped, so neither it nor its children
/// outlive the call.
pub fn run_logged(
    argv: &[OsString],
    out: &File,
    timeout: Duration,
    cancel: &Cancel,
) -> io::Result<Exit> {
    let (program, args) = argv
        .split_first()
        .ok_or_else(|| io::Error::new(io::ErrorKind::InvalidInput, "empty command"))?;
    let mut cmd = Command::new(program);
    cmd.args(args)
        .stdin(Stdio::null())
        .stdout(out.try_clone()?)
        .stderr(out.try_clone()?)
        // Unbuffered Python: the log is in order and nothing is lost if Blender crashes.
        .env("PYTHONUNBUFFERED", "1")
        .process_group(0);
    die_with_parent(&mut cmd);
    let _waiting = Waiting::new(cancel);
    // A stop asked for before the start: no Blender is started for nothing.
    if cancel.is_requested() {
        return Ok(Exit::Interrupted);
    }
    let mut child = cmd.spawn()?;
    wait_for(&mut child, timeout, cancel)
}

fn wait_for(
    child: &mut std::process::Child,
    timeout: Duration,
    cancel: &Cancel,
) -> io::Result<Exit> {
    let start = Instant::now();
    let mut pause = Duration::from_millis(2);
    loop {
        if let Some(status) = child.try_wait()? {
            return Ok(Exit::Finished(status));
        }
        if cancel.is_requested() {
            kill_group(child)?;
            return Ok(Exit::Interrupted);
        }
        let elapsed = start.elapsed();
        if elapsed >= timeout {
            kill_group(child)?;
            return Ok(Exit::TimedOut);
        }
        std::thread::sleep(pause.min(timeout - elapsed));
        pause = (pause * 2).min(Duration::from_millis(50));
    }
}

/// Asks Linux to kill the child when gloffuse dies (a child in its own process group does
/// not get the terminal's Ctrl-C), so an interrupted gloffuse leaves no Blender behind.
#[cfg(target_os = "linux")]
fn die_with_parent(cmd: &mut Command) {
    let parent = std::process::id();
    // SAFETY: the closure runs between fork and exec and calls only async-signal-safe
    // functions (prctl, getppid); it allocates nothing.
    unsafe {
        cmd.pre_exec(move || {
            if libc::prctl(libc::PR_SET_PDEATHSIG, libc::SIGKILL) == -1 {
                return Err(io::Error::last_os_error());
            }
            // The parent may have died before prctl took effect.
            if u32::try_from(libc::getppid()).ok() != Some(parent) {
                return Err(io::Error::from_raw_os_error(libc::ESRCH));
            }
            Ok(())
        });
    }
}

#[cfg(not(target_os = "linux"))]
fn die_with_parent(_cmd: &mut Command) {}

/// Runs a short command with a timeout and returns its stdout and stderr (together, lossy).
pub fn run_captured(
    argv: &[OsString],
    timeout: Duration,
    cancel: &Cancel,
) -> io::Result<(Exit, String)> {
    let out = tempfile::tempfile()?;
    let exit = run_logged(argv, &out, timeout, cancel)?;
    let mut out = out;
    let mut bytes = Vec::new();
    use std::io::{Read, Seek};
    out.rewind()?;
    out.read_to_end(&mut bytes)?;
    Ok((exit, String::from_utf8_lossy(&bytes).into_owned()))
}

/// `exited with status 1`, `was killed by signal 9`.
pub fn describe_status(status: ExitStatus) -> String {
    match (status.code(), status.signal()) {
        (Some(code), _) => format!("exited with status {code}"),
        (None, Some(sig)) => format!("was killed by signal {sig}"),
        (None, None) => format!("ended abnormally ({status})"),
    }
}

/// `2`, `0.5`, `90` — seconds as a person writes them on the command line.
pub fn format_seconds(d: Duration) -> String {
    if d.subsec_nanos() == 0 {
        d.as_secs().to_string()
    } else {
        format!("{}", (d.as_secs_f64() * 1000.0).round() / 1000.0)
    }
}

/// Joins arguments into one POSIX-shell command line (arguments with anything beyond
/// `[A-Za-z0-9_@%+=:,./-]` are single-quoted; bad UTF-8 is shown lossily).
pub fn shell_join(argv: &[OsString]) -> String {
    argv.iter()
        .map(|a| shell_quote(a))
        .collect::<Vec<_>>()
        .join(" ")
}

/// Quotes one argument for a POSIX shell.
///
/// ```
/// use gloffuse::blender::process::shell_quote;
/// assert_eq!(shell_quote("/usr/bin/blender".as_ref()), "/usr/bin/blender");
/// assert_eq!(shell_quote("it's here".as_ref()), r"'it'\''s here'");
/// assert_eq!(shell_quote("".as_ref()), "''");
/// ```
pub fn shell_quote(arg: &OsStr) -> String {
    let s = arg.to_string_lossy();
    let safe = |c: char| c.is_ascii_alphanumeric() || "_@%+=:,./-".contains(c);
    if !s.is_empty() && s.chars().all(safe) {
        s.into_owned()
    } else {
        format!("'{}'", s.replace('\'', r"'\''"))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn seconds_and_quoting() {
        assert_eq!(format_seconds(Duration::from_secs(2)), "2");
        assert_eq!(format_seconds(Duration::from_millis(1500)), "1.5");
        let argv: Vec<OsString> = vec!["blender".into(), "--".into(), "a b".into(), "$x".into()];
        assert_eq!(shell_join(&argv), "blender -- 'a b' '$x'");
    }
}
