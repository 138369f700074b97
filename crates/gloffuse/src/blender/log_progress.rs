//! A run's progress as its log tells it, read while the run goes on.
//!
//! - A render: Blender logs Cycles' status lines ("… | Remaining:00:37.44 | … | Sample
//!   1/128"; bpy, which logs none, has the furnace script print the same text). In the
//!   background Cycles reports only a few samples (often the first and the last), so the
//!   sample count alone would leave a bar standing still; but the first sample's line
//!   carries Cycles' own estimate of the time left, which is counted down here between lines.
//! - A job's own steps: the generate job prints "gloffuse step K/N: what" as each step
//!   begins (runtime.py's `log_step`).

use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use super::{Run, RunOutput, run_script};
use crate::Error;

/// The last status line Cycles logged for a render.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Status {
    pub sample: u64,
    pub samples: u64,
    /// Cycles' estimate of the seconds left, when the line has one.
    pub remaining: Option<f64>,
}

/// The last line of `log` that reports a sample ("Sample N/M"), read as a [`Status`].
pub fn last_status(log: &str) -> Option<Status> {
    let at = log.rfind("Sample ")?;
    let line = &log[log[..at].rfind('\n').map_or(0, |n| n + 1)..];
    let line = line.lines().next().unwrap_or(line);
    let counts = &log[at + "Sample ".len()..];
    let (sample, rest) = leading_number(counts)?;
    let samples = rest
        .strip_prefix('/')
        .and_then(leading_number)
        .map_or(sample, |(m, _)| m);
    let remaining = line
        .find("Remaining:")
        .and_then(|r| clock_seconds(line[r + "Remaining:".len()..].trim_start()));
    Some(Status {
        sample,
        samples,
        remaining,
    })
}

fn leading_number(text: &str) -> Option<(u64, &str)> {
    let end = text
        .find(|c: char| !c.is_ascii_digit())
        .unwrap_or(text.len());
    Some((text[..end].parse().ok()?, &text[end..]))
}

/// Cycles' clock ("MM:SS.ss" or "HH:MM:SS.ss", up to the next space or '|') in seconds.
fn clock_seconds(text: &str) -> Option<f64> {
    let clock = text.split([' ', '|']).next()?;
    let mut seconds = 0.0;
    let parts: Vec<&str> = clock.split(':').collect();
    if !(2..=3).contains(&parts.len()) {
        return None;
    }
    for part in parts {
        let value: f64 = part.parse().ok()?;
        seconds = seconds * 60.0 + value;
    }
    seconds.is_finite().then_some(seconds)
}

/// How far a render is: `done` from 0 to 1, and the seconds it still needs by Cycles'
/// estimate (none before Cycles has made one).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Estimate {
    pub done: f64,
    pub seconds_left: Option<f64>,
}

/// The most an unfinished render is said to be done: Cycles' estimate can run out before
/// the render does.
const UNFINISHED_MAX: f64 = 0.99;

impl Estimate {
    /// Where a render stands `elapsed` seconds after its process started, `since` seconds
    /// after `status` was first seen in the log. With Cycles' estimate R the render is
    /// expected to end R after that line, so it is elapsed / (elapsed + what is left) done;
    /// without one, the share of samples logged.
    pub fn of(status: Option<Status>, elapsed: f64, since: f64) -> Estimate {
        let Some(s) = status else {
            return Estimate {
                done: 0.0,
                seconds_left: None,
            };
        };
        if s.samples > 0 && s.sample >= s.samples {
            return Estimate {
                done: 1.0,
                seconds_left: Some(0.0),
            };
        }
        match s.remaining {
            Some(r) => {
                let left = (r - since).max(0.0);
                let whole = elapsed + left;
                let done = if whole > 0.0 { elapsed / whole } else { 0.0 };
                Estimate {
                    done: done.min(UNFINISHED_MAX),
                    seconds_left: Some(left),
                }
            }
            None => Estimate {
                done: (s.sample as f64 / s.samples.max(1) as f64).min(UNFINISHED_MAX),
                seconds_left: None,
            },
        }
    }
}

/// Runs `run` while a watcher reads its log every 200 ms and passes `on_estimate` where the
/// render stands (never less done than before).
pub fn run_following_render(
    run: &Run,
    on_estimate: &(dyn Fn(Estimate) + Sync),
) -> Result<RunOutput, Error> {
    let start = Instant::now();
    let mut seen: Option<(Status, Instant)> = None;
    let mut shown = 0.0f64;
    run_watching_log(run, &mut |log| {
        let status = last_status(log);
        if status.is_some() && status != seen.map(|(s, _)| s) {
            seen = status.map(|s| (s, Instant::now()));
        }
        let since = seen.map_or(0.0, |(_, at)| at.elapsed().as_secs_f64());
        let mut estimate = Estimate::of(seen.map(|(s, _)| s), start.elapsed().as_secs_f64(), since);
        // A longer new estimate holds the bar rather than moving it back.
        estimate.done = estimate.done.max(shown);
        shown = estimate.done;
        on_estimate(estimate);
    })
}

/// A step a job said it began: `done` of `total` finished, `what` next.
#[derive(Clone, Debug, PartialEq)]
pub struct Step {
    pub done: u64,
    pub total: u64,
    pub what: String,
}

const STEP_MARK: &str = "gloffuse step ";

/// Every "gloffuse step K/N: what" line of `log` (each starting a line), in order.
pub fn steps(log: &str) -> Vec<Step> {
    log.lines()
        .filter_map(|line| {
            let rest = line.strip_prefix(STEP_MARK)?;
            let (counts, what) = rest.split_once(": ")?;
            let (done, total) = counts.split_once('/')?;
            Some(Step {
                done: done.parse().ok()?,
                total: total.parse().ok()?,
                what: what.to_string(),
            })
        })
        .collect()
}

/// Runs `run` while a watcher reads its log every 200 ms and passes `on_step` each step the
/// job says it began, in order, once (a quick step is told late rather than skipped).
pub fn run_following_steps(
    run: &Run,
    on_step: &mut (dyn FnMut(&Step) + Send),
) -> Result<RunOutput, Error> {
    let mut told = 0;
    run_watching_log(run, &mut |log| {
        let all = steps(log);
        for step in all.iter().skip(told) {
            on_step(step);
        }
        told = told.max(all.len());
    })
}

/// Runs `run` while a watcher hands `on_log` the log's text every 200 ms, and once more
/// when the run has ended, so that what it logged last is read too.
fn run_watching_log(run: &Run, on_log: &mut (dyn FnMut(&str) + Send)) -> Result<RunOutput, Error> {
    let finished = AtomicBool::new(false);
    std::thread::scope(|scope| {
        scope.spawn(|| {
            loop {
                let last = finished.load(Ordering::Acquire);
                if let Ok(bytes) = std::fs::read(&run.log) {
                    on_log(&String::from_utf8_lossy(&bytes));
                }
                if last {
                    break;
                }
                std::thread::sleep(Duration::from_millis(200));
            }
        });
        let outcome = run_script(run);
        finished.store(true, Ordering::Release);
        outcome
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Lines as Blender 3.4.1 wrote them in a verify run (Cycles CPU, 128 samples).
    const BLENDER_34: &str = "\
Fra:1 Mem:74.82M (Peak 75.07M) | Time:00:01.00 | Mem:83.02M, Peak:83.02M | Scene, ViewLayer | Sample 0/128
Fra:1 Mem:76.89M (Peak 76.89M) | Time:00:01.30 | Remaining:00:37.44 | Mem:85.08M, Peak:85.08M | Scene, ViewLayer | Sample 1/128
";

    #[test]
    fn blender_34_lines_give_the_sample_and_cycles_estimate() {
        let s = last_status(BLENDER_34).unwrap();
        assert_eq!(s.sample, 1);
        assert_eq!(s.samples, 128);
        assert!((s.remaining.unwrap() - 37.44).abs() < 1e-9);
        let done = format!(
            "{BLENDER_34}Fra:1 Mem:78.95M (Peak 83.08M) | Time:00:14.21 | Mem:85.08M, Peak:85.08M | Scene, ViewLayer | Sample 128/128\nFra:1 | Finished\n"
        );
        let s = last_status(&done).unwrap();
        assert_eq!((s.sample, s.samples, s.remaining), (128, 128, None));
    }

    #[test]
    fn the_furnace_scripts_lines_from_bpy_are_read_alike() {
        // What bpy 5.0.1's render_stats handler receives, as furnace.py prints it.
        let log = "gloffuse render: Mem: 2M | Sample 0/64\n\
                   gloffuse render: Remaining: 01:02:03.50 | Mem: 2M | Sample 1/64\n";
        let s = last_status(log).unwrap();
        assert_eq!((s.sample, s.samples), (1, 64));
        assert_eq!(s.remaining, Some(3723.5));
    }

    #[test]
    fn a_log_without_samples_or_with_a_bad_clock_says_so() {
        assert_eq!(last_status("Fra:1 | Updating Scene BVH\n"), None);
        let s = last_status("Remaining:soon | Sample 3/8").unwrap();
        assert_eq!((s.sample, s.samples, s.remaining), (3, 8, None));
        assert_eq!(last_status("Sample x/8"), None);
    }

    #[test]
    fn step_lines_are_read_in_order() {
        let log = "Info: something\ngloffuse step 0/15: building Gloffuse (GGX) and its groups\n\
                   gloffuse step 3/15: rendering the preview of Gloffuse View (GGX)\n\
                   Fra:1 | Sample 1/64\n";
        let all = steps(log);
        assert_eq!(all.len(), 2);
        assert_eq!((all[1].done, all[1].total), (3, 15));
        assert_eq!(all[1].what, "rendering the preview of Gloffuse View (GGX)");
        // Only a line that starts with the mark; counts must be numbers.
        assert_eq!(steps("Info: gloffuse step 1/2: x\n"), []);
        assert_eq!(steps("gloffuse step a/2: x\n"), []);
    }

    #[test]
    fn the_estimate_counts_cycles_remaining_time_down() {
        let first = Status {
            sample: 1,
            samples: 128,
            remaining: Some(30.0),
        };
        // Seen 10 s into the run; 5 s later: 15 s gone, 25 s left.
        let e = Estimate::of(Some(first), 15.0, 5.0);
        assert_eq!(e.seconds_left, Some(25.0));
        assert!((e.done - 15.0 / 40.0).abs() < 1e-12);
        // The estimate runs out before the render does: not done, nothing left.
        let e = Estimate::of(Some(first), 60.0, 50.0);
        assert_eq!((e.done, e.seconds_left), (UNFINISHED_MAX, Some(0.0)));
        // The last sample ends it; no line yet says nothing.
        let last = Status {
            sample: 128,
            ..first
        };
        assert_eq!(Estimate::of(Some(last), 60.0, 0.0).done, 1.0);
        assert_eq!(Estimate::of(None, 3.0, 0.0).seconds_left, None);
        // No estimate on the line: the share of samples.
        let plain = Status {
            sample: 32,
            samples: 128,
            remaining: None,
        };
        assert_eq!(Estimate::of(Some(plain), 9.0, 1.0).done, 0.25);
    }
}
