//! `gloffuse lut --kind coat`: the layered shader's coat table for real-time renderers, read
//! back from the EXR with the exr crate and checked texel by texel against independent
//! oracles: the brute-force Fresnel-weighted albedo (`common::oracle`) for R, the plain
//! albedo for G, and the closed-form limits (no coat at IOR 1).
//!
//! Tier: fast (no Blender; `scripts/test.sh --fast` runs it).

mod common;

use exr::prelude::*;
use gloffuse::lut::{Bits, Format, Kind, LutOptions, lut};
use gloffuse::measure::coat::{SLICES, coat_albedo, fresnel_average};
use gloffuse::measure::{AlbedoIntegrator, Distribution, Glossy, Masking, Roughness, fresnel};
use gloffuse::progress::Quiet;
use rayon::prelude::*;

const SIZE: usize = 6;

/// The EXR's channels R and G, row-major, first row first.
fn read_rg(path: &std::path::Path) -> (usize, usize, Vec<f32>, Vec<f32>) {
    let image = read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .first_valid_layer()
        .all_attributes()
        .from_file(path)
        .unwrap();
    let layer = &image.layer_data;
    let channel = |name: &str| -> Vec<f32> {
        let c = layer
            .channel_data
            .list
            .iter()
            .find(|c| c.name.to_string() == name)
            .unwrap_or_else(|| panic!("no channel {name}"));
        match &c.sample_data {
            FlatSamples::F32(v) => v.clone(),
            other => panic!("expected 32-bit floats, got {other:?}"),
        }
    };
    (layer.size.0, layer.size.1, channel("R"), channel("G"))
}

#[test]
fn the_coat_table_is_the_fresnel_weighted_coat_in_slices() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("coat.exr");
    let mut args = LutOptions::new(Kind::Coat, &path);
    args.size = Some(SIZE as u32);
    args.bits = Bits::Float;
    args.distribution = Some(Distribution::Beckmann);
    let summary = lut(&args, &Quiet).unwrap();
    assert_eq!(summary.format, Format::Exr);
    let ior = summary
        .ior
        .clone()
        .expect("a coat summary lists its slices");
    assert_eq!(ior.len(), SLICES);
    assert_eq!(ior[0], 1.0);
    assert!((ior[SLICES - 1] - 3.0).abs() < 1e-12);
    let (width, height, r, g) = read_rg(&path);
    assert_eq!((width, height), (SIZE * SLICES, SIZE));

    let q = AlbedoIntegrator::default();
    let centre = |i: usize| (i as f64 + 0.5) / SIZE as f64;
    let lobe = |x: usize| {
        Glossy::new(
            Distribution::Beckmann,
            Masking::HeightCorrelated,
            Roughness::new(centre(x)).unwrap(),
        )
    };
    for y in 0..SIZE {
        for x in 0..SIZE {
            let e = q.directional_albedo(&lobe(x), centre(y));
            for k in 0..SLICES {
                let at = y * width + k * SIZE + x;
                // G is E in every slice; R is 0 without a coat and grows with the index
                // (except at grazing views, where a denser coat reflects less: F(cos 85°)
                // is 0.642 at IOR 2 and 0.613 at IOR 3).
                assert!((f64::from(g[at]) - e).abs() < 1e-6, "G at ({x}, {y}, {k})");
                if k == 0 {
                    assert_eq!(r[at], 0.0, "IOR 1 reflects nothing");
                } else {
                    let grazing = centre(y) < 0.2;
                    assert!(
                        grazing || r[at] > r[at - SIZE],
                        "A grows with the index at ({x}, {y}, {k})"
                    );
                    assert!(r[at] > 0.0 && r[at] <= 1.0);
                }
            }
        }
    }
    // R against the brute force of the Fresnel-weighted albedo (it shares only the BSDF
    // with the quadrature), at a few texels of a glass-like and the densest slice.
    let texels: Vec<(usize, usize, usize)> = [(1, 4, 7), (4, 1, 7), (5, 5, 11), (2, 0, 11)]
        .into_iter()
        .collect();
    let failures: Vec<String> = texels
        .par_iter()
        .filter_map(|&(x, y, k)| {
            let (glossy, mu, eta) = (lobe(x), centre(y), ior[k]);
            let e_f = common::oracle::brute_force_weighted(&glossy, mu, 1500, 1500, &|c| {
                fresnel::dielectric(c, eta)
            });
            let e = common::oracle::brute_force_albedo(&glossy, mu, 1500, 1500);
            let want = coat_albedo(e_f, e, fresnel_average(eta), q.average_albedo(&glossy));
            let got = f64::from(r[y * width + k * SIZE + x]);
            ((got - want).abs() > 2e-4).then(|| format!("({x}, {y}, IOR {eta}): {got} vs {want}"))
        })
        .collect();
    assert!(failures.is_empty(), "{failures:#?}");
}

#[test]
fn the_coat_table_refuses_samples_and_oversized_atlases() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("coat.exr");
    let mut args = LutOptions::new(Kind::Coat, &path);
    args.samples = Some(64);
    let message = with_fields(&lut(&args, &Quiet).unwrap_err());
    assert!(message.starts_with("invalid <Samples>"), "{message}");
    args.samples = None;
    args.size = Some(2048);
    let message = with_fields(&lut(&args, &Quiet).unwrap_err());
    assert!(
        message.starts_with("invalid <Size>") && message.contains("1024"),
        "{message}"
    );
    assert!(!path.exists(), "nothing written on bad input");
}

/// The message with each field shown as `<Field>`: what the CLI turns into its flags.
fn with_fields(e: &gloffuse::Error) -> String {
    e.render(|f| format!("<{f:?}>"))
}
