//! Issue 25 (3): a render's progress follows Cycles' own estimate in every real Blender.
//! Blender 3.4's binary logs Cycles' status lines itself; bpy logs none, so the furnace
//! script prints what its render_stats handler receives. Either way the verify render must
//! report Cycles' "Remaining" estimate while it runs, move forward only, and end done.

mod common;

use std::sync::Mutex;

use gloffuse::blender::probe;
use gloffuse::measure::{Distribution, Roughness};
use gloffuse::progress::Progress;
use gloffuse::verify::{VerifyOptions, verify_with};

/// Records what the render tells its progress.
#[derive(Default)]
struct Recorded {
    begun: Mutex<Vec<String>>,
    estimates: Mutex<Vec<(f64, Option<f64>)>>,
}

impl Progress for Recorded {
    fn begin_estimated(&self, message: &str) {
        self.begun.lock().unwrap().push(message.to_string());
    }
    fn estimate(&self, done: f64, seconds_left: Option<f64>) {
        self.estimates.lock().unwrap().push((done, seconds_left));
    }
}

#[test]
fn the_verify_render_follows_cycles_estimate_in_every_blender() {
    for (label, program) in common::blender::real_blenders() {
        let blender = probe(&program).unwrap();
        let mut options = VerifyOptions {
            distributions: vec![Distribution::Ggx],
            roughness: [0.3, 0.7].map(|r| Roughness::new(r).unwrap()).to_vec(),
            ..VerifyOptions::default()
        };
        // Long enough that the watcher (every 200 ms) sees a line between the first
        // sample and the last.
        options.render.samples = 512;
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
}
