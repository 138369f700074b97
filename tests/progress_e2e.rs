//! Issue 25 (3, 4): what long runs tell their progress, in real Blender.
//!
//! - A render follows Cycles' own estimate in every Blender. Blender 3.4's binary logs
//!   Cycles' status lines itself; bpy logs none, so the furnace script prints what its
//!   render_stats handler receives. Either way the verify render must report Cycles'
//!   "Remaining" estimate while it runs, move forward only, and stay within 0 to 1.
//! - `generate --blend` tells each distribution's groups, each preview and the save as
//!   they begin.
//!
//! Tier: blender (needs the Blenders and tools `scripts/test.sh` installs).

mod common;

use std::path::PathBuf;

use std::sync::Mutex;

use gloffuse::blender::{BlenderOptions, probe};
use gloffuse::generate::{GenerateOptions, Mode, generate};
use gloffuse::measure::{Distribution, Roughness};
use gloffuse::progress::Progress;
use gloffuse::verify::{VerifyOptions, verify_with};

/// Records what the render tells its progress.
#[derive(Default)]
struct Recorded {
    begun: Mutex<Vec<String>>,
    estimates: Mutex<Vec<(f64, Option<f64>)>>,
    steps: Mutex<Vec<u64>>,
    totals: Mutex<Vec<u64>>,
    doing: Mutex<Vec<String>>,
}

impl Progress for Recorded {
    fn begin_estimated(&self, message: &str) {
        self.begun.lock().unwrap().push(message.to_string());
    }
    fn estimate(&self, done: f64, seconds_left: Option<f64>) {
        self.estimates.lock().unwrap().push((done, seconds_left));
    }
    fn begin(&self, _message: &str, steps: u64) {
        self.totals.lock().unwrap().push(steps);
    }
    fn set(&self, done: u64) {
        self.steps.lock().unwrap().push(done);
    }
    fn doing(&self, what: &str) {
        self.doing.lock().unwrap().push(what.to_string());
    }
}

#[test]
fn generate_tells_each_group_preview_and_the_save() {
    let Some(program) = common::blender::real_blender("3.4") else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let options = GenerateOptions {
        blend: Some(dir.path().join("library.blend")),
        modes: vec![Mode::Roughness, Mode::View],
        blender: BlenderOptions {
            program: Some(program),
            ..BlenderOptions::default()
        },
        ..GenerateOptions::default()
    };
    let recorded = Recorded::default();
    let generated = generate(&options, &recorded).unwrap();

    // Independently of the job's own count: one step per distribution, one per
    // previewed shader group (the "Gloffuse (…)" and "Gloffuse View (…)" ones), the save.
    let shaders: Vec<&String> = generated
        .groups
        .iter()
        .filter(|g| g.starts_with("Gloffuse (") || g.starts_with("Gloffuse View ("))
        .collect();
    assert_eq!(shaders.len(), 6, "{:?}", generated.groups);
    let total = 3 + shaders.len() as u64 + 1;
    assert_eq!(*recorded.totals.lock().unwrap(), [total]);
    let doing = recorded.doing.lock().unwrap();
    for shader in &shaders {
        assert!(
            doing
                .iter()
                .any(|d| d.ends_with(&format!("preview of {shader}"))),
            "no preview step for {shader}: {doing:?}"
        );
    }
    for distribution in ["Beckmann", "GGX", "Ashikhmin-Shirley"] {
        assert!(
            doing
                .iter()
                .any(|d| d.contains(&format!("building Gloffuse ({distribution})"))),
            "{doing:?}"
        );
    }
    assert!(
        doing.last().unwrap().ends_with("saving the .blend"),
        "{doing:?}"
    );
    assert!(
        doing.iter().all(|d| d.starts_with("Blender 3.4")),
        "{doing:?}"
    );
    // Each step told once, in order, even the quick ones between two reads of the log.
    let steps = recorded.steps.lock().unwrap();
    assert_eq!(*steps, (0..total).collect::<Vec<_>>(), "{doing:?}");
}

fn the_verify_render_follows_cycles_estimate_in_every_blender(
    label: &'static str,
    program: PathBuf,
) {
    let blender = probe(&program).unwrap();
    let mut options = VerifyOptions {
        distributions: vec![Distribution::Ggx],
        roughness: [0.3, 0.7].map(|r| Roughness::new(r).unwrap()).to_vec(),
        ..VerifyOptions::default()
    };
    // Long enough that the watcher (every 200 ms) sees a line between the first
    // sample and the last.
    options.samples = Some(512);
    let recorded = Recorded::default();
    verify_with(&blender, &options, &recorded).unwrap();

    let begun = recorded.begun.lock().unwrap();
    assert_eq!(begun.len(), 1, "Blender {label}: {begun:?}");
    assert!(begun[0].starts_with("rendering"), "{begun:?}");
    let estimates = recorded.estimates.lock().unwrap();
    let with_cycles_estimate: Vec<_> = estimates
        .iter()
        .filter(|(done, left)| *done < 1.0 && left.is_some_and(|s| s > 0.0))
        .collect();
    assert!(
        !with_cycles_estimate.is_empty(),
        "Blender {label}: no estimate from Cycles' Remaining was seen: {estimates:?}"
    );
    for pair in estimates.windows(2) {
        assert!(
            pair[1].0 >= pair[0].0,
            "Blender {label}: the bar went back: {pair:?}"
        );
    }
    for (done, _) in estimates.iter() {
        assert!((0.0..=1.0).contains(done), "Blender {label}: {done}");
    }
}

common::blender::per_blender!(the_verify_render_follows_cycles_estimate_in_every_blender);
