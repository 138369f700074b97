//! The lookup tables: every container read back by an independent reader (exr, ddsfile,
//! ktx2), split-sum values against oracles that share no code with the fast kernels,
//! Kulla–Conty against the albedo integrator and an energy balance, and bad input.
//!
//! Tier: fast (no Blender; `scripts/test.sh --fast` runs it).

use gloffuse::lut::split_sum::{
    Estimate, Rule, Sampler, split_sum, split_sum_texel_quadrature, split_sum_texel_sampled,
};
use gloffuse::lut::{
    Bits, Bsdf, Format, GModel, Kind, LutOptions, Method, Spec, Table, kulla_conty, lut,
};
use gloffuse::measure::BlenderVersion;
use gloffuse::measure::{AlbedoIntegrator, Distribution, Glossy, Masking, Quadrature, Roughness};
use gloffuse::progress::{Progress, Quiet};
use gloffuse::{Error, Field};
use half::f16;
use std::io::Cursor;
use std::path::Path;

fn coord(i: usize, n: usize) -> f64 {
    (i as f64 + 0.5) / n as f64
}

/// Small, fast requests of both kinds.
fn small(kind: Kind, out: &Path, format: Format, bits: Bits) -> LutOptions {
    let mut args = LutOptions::new(kind, out);
    args.size = Some(match kind {
        Kind::SplitSum => 24,
        Kind::KullaConty | Kind::Albedo | Kind::Coat => 8,
        Kind::Anisotropic | Kind::Glass => 4,
    });
    // Only Kulla–Conty samples: the albedo and coat tables and split-sum's default method
    // are quadrature.
    args.samples = (kind == Kind::KullaConty).then_some(256);
    args.format = Some(format);
    args.bits = bits;
    args
}

/// The value a reader must find for `v` stored at `bits`.
fn stored(v: f32, bits: Bits) -> f32 {
    match bits {
        Bits::Half => f16::from_f32(v).to_f32(),
        Bits::Float => v,
    }
}

fn decode(bytes: &[u8], bits: Bits) -> Vec<f32> {
    match bits {
        Bits::Half => bytes
            .chunks_exact(2)
            .map(|b| f16::from_le_bytes([b[0], b[1]]).to_f32())
            .collect(),
        Bits::Float => bytes
            .chunks_exact(4)
            .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
            .collect(),
    }
}

/// Texel values must equal the computed table: bit for bit (compare bits, not ≈).
fn assert_same_texels(found: &[f32], table: &Table, bits: Bits, what: &str) {
    assert_eq!(found.len(), table.data.len(), "{what}: texel count");
    for (i, (&f, &t)) in found.iter().zip(&table.data).enumerate() {
        assert_eq!(
            f.to_bits(),
            stored(t, bits).to_bits(),
            "{what}: value {i} is {f}, computed {t}"
        );
    }
}

const KINDS: [Kind; 6] = Kind::ALL;
const BITS: [Bits; 2] = [Bits::Half, Bits::Float];

#[test]
fn exr_reads_back_with_the_exr_crate() {
    use exr::prelude::*;
    let dir = tempfile::tempdir().unwrap();
    for kind in KINDS {
        for bits in BITS {
            let path = dir.path().join(format!("{kind:?}-{}.exr", bits.count()));
            let args = small(kind, &path, Format::Exr, bits);
            let table = Spec::from_options(&args).unwrap().compute(&Quiet);
            let summary = lut(&args, &Quiet).unwrap();
            assert_eq!(
                summary.bytes as u64,
                std::fs::metadata(&path).unwrap().len()
            );
            let bytes = std::fs::read(&path).unwrap();
            let image = read()
                .no_deep_data()
                .largest_resolution_level()
                .all_channels()
                .first_valid_layer()
                .all_attributes()
                .from_buffered(Cursor::new(bytes))
                .unwrap();
            let layer = &image.layer_data;
            assert_eq!(layer.size, Vec2(table.width, table.height));
            assert_eq!(layer.encoding.compression, Compression::ZIP16);
            let names: Vec<String> = layer
                .channel_data
                .list
                .iter()
                .map(|c| c.name.to_string())
                .collect();
            let mut expected: Vec<String> = table.channels.iter().map(|s| s.to_string()).collect();
            expected.sort();
            assert_eq!(
                names, expected,
                "{kind:?}: EXR channels (sorted, as EXR stores them)"
            );
            for channel in &layer.channel_data.list {
                let c = table
                    .channels
                    .iter()
                    .position(|&n| channel.name.to_string() == n)
                    .unwrap();
                let values: Vec<f32> = match (&channel.sample_data, bits) {
                    (FlatSamples::F16(v), Bits::Half) => v.iter().map(|h| h.to_f32()).collect(),
                    (FlatSamples::F32(v), Bits::Float) => v.clone(),
                    (other, _) => panic!("{kind:?} {bits:?}: unexpected sample type {other:?}"),
                };
                let column = Table {
                    width: table.width,
                    height: table.height,
                    channels: &["X"],
                    data: (0..table.width * table.height)
                        .map(|i| table.data[i * table.channels.len() + c])
                        .collect(),
                };
                assert_same_texels(
                    &values,
                    &column,
                    bits,
                    &format!("EXR {kind:?} {}", channel.name),
                );
            }
        }
    }
}

#[test]
fn dds_reads_back_with_ddsfile() {
    use ddsfile::{D3D10ResourceDimension, Dds, DxgiFormat};
    let dir = tempfile::tempdir().unwrap();
    for kind in KINDS {
        for bits in BITS {
            let path = dir.path().join(format!("{kind:?}-{}.dds", bits.count()));
            let args = small(kind, &path, Format::Dds, bits);
            let table = Spec::from_options(&args).unwrap().compute(&Quiet);
            let summary = lut(&args, &Quiet).unwrap();
            let dds = Dds::read(std::fs::File::open(&path).unwrap()).unwrap();
            let expected = match (kind, bits) {
                (
                    Kind::SplitSum | Kind::Albedo | Kind::Coat | Kind::Anisotropic | Kind::Glass,
                    Bits::Half,
                ) => DxgiFormat::R16G16_Float,
                (
                    Kind::SplitSum | Kind::Albedo | Kind::Coat | Kind::Anisotropic | Kind::Glass,
                    Bits::Float,
                ) => DxgiFormat::R32G32_Float,
                (Kind::KullaConty, Bits::Half) => DxgiFormat::R16G16B16A16_Float,
                (Kind::KullaConty, Bits::Float) => DxgiFormat::R32G32B32A32_Float,
            };
            assert_eq!(dds.get_dxgi_format(), Some(expected));
            let header10 = dds.header10.as_ref().expect("a DX10 header");
            assert_eq!(
                header10.resource_dimension,
                D3D10ResourceDimension::Texture2D
            );
            assert_eq!(header10.array_size, 1);
            assert_eq!(dds.get_width() as usize, table.width);
            assert_eq!(dds.get_height() as usize, table.height);
            assert_eq!(dds.get_num_mipmap_levels(), 1);
            assert_eq!(
                dds.get_pitch(),
                Some(table.width as u32 * bits.count() / 8 * table.channels.len() as u32)
            );
            assert_eq!(
                summary.pixel_format,
                format!("DXGI_FORMAT_{expected:?}").to_uppercase()
            );
            assert_same_texels(&decode(&dds.data, bits), &table, bits, "DDS");
        }
    }
}

#[test]
fn ktx2_reads_back_with_the_ktx2_crate() {
    let dir = tempfile::tempdir().unwrap();
    for kind in KINDS {
        for bits in BITS {
            let path = dir.path().join(format!("{kind:?}-{}.ktx2", bits.count()));
            let args = small(kind, &path, Format::Ktx, bits);
            let table = Spec::from_options(&args).unwrap().compute(&Quiet);
            let summary = lut(&args, &Quiet).unwrap();
            let bytes = std::fs::read(&path).unwrap();
            let reader = ktx2::Reader::new(&bytes[..]).expect("a valid KTX2 file");
            let header = reader.header();
            let format = match (kind, bits) {
                (
                    Kind::SplitSum | Kind::Albedo | Kind::Coat | Kind::Anisotropic | Kind::Glass,
                    Bits::Half,
                ) => ktx2::Format::R16G16_SFLOAT,
                (
                    Kind::SplitSum | Kind::Albedo | Kind::Coat | Kind::Anisotropic | Kind::Glass,
                    Bits::Float,
                ) => ktx2::Format::R32G32_SFLOAT,
                (Kind::KullaConty, Bits::Half) => ktx2::Format::R16G16B16A16_SFLOAT,
                (Kind::KullaConty, Bits::Float) => ktx2::Format::R32G32B32A32_SFLOAT,
            };
            assert_eq!(header.format, Some(format));
            assert_eq!(header.type_size, bits.count() / 8);
            assert_eq!(header.pixel_width as usize, table.width);
            assert_eq!(header.pixel_height as usize, table.height);
            assert_eq!(header.pixel_depth, 0);
            assert_eq!(header.layer_count, 0);
            assert_eq!(header.face_count, 1);
            assert_eq!(header.level_count, 1);
            assert_eq!(header.supercompression_scheme, None);
            assert_eq!(
                (header.index.sgd_byte_offset, header.index.sgd_byte_length),
                (0, 0)
            );
            assert_eq!(
                header.index.dfd_byte_offset,
                80 + 24,
                "the DFD follows the level index"
            );
            assert_eq!(header.index.dfd_byte_offset % 4, 0);
            assert_eq!(header.index.kvd_byte_offset % 4, 0);
            assert_eq!(
                summary.pixel_format,
                format!("VK_FORMAT_{format:?}"),
                "the summary names the Vulkan format"
            );

            // The DFD equals what the ktx2 crate's own generator makes for this format, and
            // the bytes we wrote are exactly its serialisation.
            let (expected_dfd, type_size) = ktx2::dfd::Basic::from_format(format).unwrap();
            assert_eq!(type_size, header.type_size);
            assert_eq!(
                reader.dfd_blocks(),
                &[ktx2::dfd::Block::Basic(expected_dfd.clone())]
            );
            let start = header.index.dfd_byte_offset as usize;
            let total = u32::from_le_bytes(bytes[start..start + 4].try_into().unwrap());
            assert_eq!(total, header.index.dfd_byte_length);
            assert_eq!(
                &bytes[start + 4..start + total as usize],
                &ktx2::dfd::Block::Basic(expected_dfd).to_vec()[..]
            );
            let basic = reader.basic_dfd().unwrap();
            assert_eq!(
                basic.bytes_planes[0] as u32,
                bits.count() / 8 * table.channels.len() as u32
            );
            assert_eq!(
                basic.transfer_function,
                Some(ktx2::TransferFunction::Linear)
            );

            let writer = reader.writer().unwrap().trim_end_matches('\0');
            assert!(writer.starts_with("gloffuse "), "KTXwriter = {writer:?}");

            let levels: Vec<_> = reader.levels().collect();
            assert_eq!(levels.len(), 1);
            assert_eq!(
                levels[0].uncompressed_byte_length as usize,
                levels[0].data.len()
            );
            let offset = levels[0].data.as_ptr() as usize - bytes.as_ptr() as usize;
            let texel = (bits.count() / 8) as usize * table.channels.len();
            assert_eq!(
                offset % texel.max(4),
                0,
                "level data aligned to lcm(texel size, 4)"
            );
            assert_eq!(offset + levels[0].data.len(), bytes.len());
            assert_same_texels(&decode(levels[0].data, bits), &table, bits, "KTX2");
        }
    }
}

#[test]
fn half_floats_round_to_nearest() {
    // One table, both depths: the 16-bit file holds the nearest half of every 32-bit value.
    let dir = tempfile::tempdir().unwrap();
    let mut values = Vec::new();
    for bits in BITS {
        let path = dir.path().join(format!("t{}.ktx2", bits.count()));
        lut(&small(Kind::SplitSum, &path, Format::Ktx, bits), &Quiet).unwrap();
        let bytes = std::fs::read(&path).unwrap();
        let reader = ktx2::Reader::new(&bytes[..]).unwrap();
        values.push(decode(reader.levels().next().unwrap().data, bits));
    }
    for (h, f) in values[0].iter().zip(&values[1]) {
        let err = (h - f).abs();
        // Half has 11 significant bits: half an ulp below 1 is at most 2^-12.
        assert!(
            err <= 2f32.powi(-12) * f.abs().max(2f32.powi(-14)) * 2.0 + 1e-7,
            "{h} vs {f}"
        );
    }
}

// ---- split-sum values ----

const QUADRATURE: Estimate = Estimate::Quadrature(Rule {
    azimuth: 12,
    pole: 24,
    tail: 16,
});

#[test]
fn the_default_method_is_the_default_rule() {
    assert_eq!(QUADRATURE, Estimate::Quadrature(Rule::default()));
    let args = LutOptions::new(Kind::SplitSum, "unused.exr");
    assert_eq!(
        Spec::from_options(&args).unwrap(),
        Spec {
            kind: Kind::SplitSum,
            size: 512,
            bsdf: Bsdf::SplitSum {
                g_model: GModel::Ue4,
                estimate: QUADRATURE,
            },
        }
    );
}

#[test]
fn split_sum_mirror_limit_is_one() {
    // Column 0 of a 256 table: r = 1/512, α ≈ 4e-6 — a mirror. Then H = N, V·H = N·V and
    // N·L = N·V, so scale + bias = G(V, V)/G1_Smith(V) and bias = (1 − N·V)⁵ of that, to
    // O(α). Height-correlated: (1 + Λ)/(1 + 2Λ) with Λ ~ α² tan² θ / 4, i.e. 1. UE4:
    // Schlick's G1(N·V)² with k = α/2, which is 1 − 3.8e-5 at N·V = 0.1.
    let n = 256;
    let alpha = coord(0, n).powi(2);
    for g in [GModel::Ue4, GModel::HeightCorrelated] {
        for (estimate, tol) in [
            (QUADRATURE, 1e-5),
            (Estimate::Classic { samples: 256 }, 1e-3),
        ] {
            let t = split_sum(n, g, estimate, &Quiet);
            for y in (n / 10..n).step_by(7) {
                let nov = coord(y, n);
                let e = match g {
                    GModel::Ue4 => {
                        let k = alpha / 2.0;
                        (nov / (nov * (1.0 - k) + k)).powi(2)
                    }
                    GModel::HeightCorrelated => 1.0,
                };
                let (s, b) = (f64::from(t[y * n * 2]), f64::from(t[y * n * 2 + 1]));
                assert!(
                    (s + b - e).abs() < tol,
                    "{g:?} {estimate:?} N·V {nov}: {s} + {b}, expected {e}"
                );
                assert!(
                    (b - e * (1.0 - nov).powi(5)).abs() < tol,
                    "{g:?} {estimate:?} N·V {nov}: bias {b}"
                );
            }
        }
    }
}

#[test]
fn the_quadrature_matches_a_converged_sampled_estimate() {
    // The plain-f64 visible-normal estimator (its own sampling; only the masking formula is
    // shared with the quadrature) with 2^20
    // samples is within 2e-6 of the converged values (measured: within 1.9e-6 of the
    // quadrature's fine rule on 672 texels of a 512² subset, `cargo bench --bench lut`), so
    // the table's own error bound of 5e-5 is what this checks — including the most grazing
    // row and the narrowest lobes, where the quadrature is hardest (its measured worst,
    // 2.1e-5, is at (8, 0)).
    let n = 512;
    let texels = [
        (0, 0),
        (8, 0),
        (9, 0),
        (17, 0),
        (40, 1),
        (200, 0),
        (511, 0),
        (511, 2),
        (3, 30),
        (60, 100),
        (250, 256),
        (400, 500),
        (511, 511),
    ];
    for g in [GModel::Ue4, GModel::HeightCorrelated] {
        let t = split_sum(n, g, QUADRATURE, &Quiet);
        for &(x, y) in &texels {
            let (s, b) = split_sum_texel_sampled(
                coord(x, n),
                coord(y, n),
                1 << 20,
                g,
                Sampler::VisibleNormals,
            );
            let i = (y * n + x) * 2;
            let (ts, tb) = (f64::from(t[i]), f64::from(t[i + 1]));
            assert!(
                (ts - s).abs() < 5e-5 && (tb - b).abs() < 5e-5,
                "{g:?} texel ({x}, {y}): table ({ts:.6}, {tb:.6}), sampled ({s:.6}, {b:.6})"
            );
        }
    }
}

#[test]
fn the_quadrature_gives_ggx_closed_form_at_r_1_looking_straight_on() {
    // GGX with α = 1 at N·V = 1 with Smith height-correlated G: E = 1 − ln 2
    // (docs/PHYSICS.md §10), and scale + bias = E.
    let (s, b) = split_sum_texel_quadrature(1.0, 1.0, GModel::HeightCorrelated, Rule::default());
    let e = 1.0 - std::f64::consts::LN_2;
    assert!((s + b - e).abs() < 1e-6, "{} vs {e}", s + b);
}

#[test]
fn fast_kernels_equal_the_plain_f64_rules() {
    // Same nodes or points, same formulas: only f32 rounding may differ.
    let n = 32;
    let texels = [(0, 0), (5, 1), (17, 9), (31, 31), (25, 3), (2, 28)];
    for g in [GModel::Ue4, GModel::HeightCorrelated] {
        let t = split_sum(n, g, QUADRATURE, &Quiet);
        for &(x, y) in &texels {
            let (s, b) = split_sum_texel_quadrature(coord(x, n), coord(y, n), g, Rule::default());
            let i = (y * n + x) * 2;
            // Measured: within 2e-7 on a 512² subset.
            assert!(
                (f64::from(t[i]) - s).abs() < 1e-6 && (f64::from(t[i + 1]) - b).abs() < 1e-6,
                "{g:?} quadrature ({x}, {y}): ({}, {}) vs ({s}, {b})",
                t[i],
                t[i + 1]
            );
        }
        let t = split_sum(n, g, Estimate::Classic { samples: 333 }, &Quiet);
        for &(x, y) in &texels {
            let (s, b) =
                split_sum_texel_sampled(coord(x, n), coord(y, n), 333, g, Sampler::Classic);
            let i = (y * n + x) * 2;
            let tol = 2e-5 * (1.0 + s.abs().max(b.abs()) * 10.0);
            assert!(
                (f64::from(t[i]) - s).abs() < tol && (f64::from(t[i + 1]) - b).abs() < tol,
                "{g:?} classic ({x}, {y}): ({}, {}) vs ({s}, {b})",
                t[i],
                t[i + 1]
            );
        }
    }
}

#[test]
fn split_sum_is_identical_for_any_thread_count() {
    let with = |threads, estimate| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| split_sum(48, GModel::HeightCorrelated, estimate, &Quiet))
    };
    let bits = |t: &[f32]| t.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
    for estimate in [QUADRATURE, Estimate::Classic { samples: 100 }] {
        let one = with(1, estimate);
        for threads in [2, 3, 7] {
            assert_eq!(
                bits(&one),
                bits(&with(threads, estimate)),
                "{estimate:?}, {threads} threads"
            );
        }
    }
}

#[test]
fn height_correlated_scale_plus_bias_is_the_cycles_albedo() {
    // With Smith height-correlated G, scale + bias is exactly the directional albedo of
    // Cycles' GGX (Blender ≥ 3.6), which the albedo integrator computes by quadrature over
    // H in its own variables (no shared code) — including at grazing views, where the
    // classic estimator is off by 1e-2.
    let n = 128;
    let t = split_sum(n, GModel::HeightCorrelated, QUADRATURE, &Quiet);
    let fine = AlbedoIntegrator::new(Quadrature {
        theta: 64,
        phi: 24,
        mu: 32,
    });
    for &(x, y) in &[
        (0, 0),
        (3, 0),
        (10, 1),
        (30, 0),
        (60, 2),
        (127, 0),
        (20, 64),
        (90, 100),
        (127, 127),
    ] {
        let glossy = Glossy::new(
            Distribution::Ggx,
            Masking::HeightCorrelated,
            Roughness::new(coord(x, n)).unwrap(),
        );
        let e = fine.directional_albedo(&glossy, coord(y, n));
        let i = (y * n + x) * 2;
        let sum = f64::from(t[i]) + f64::from(t[i + 1]);
        assert!(
            (sum - e).abs() < 5e-5,
            "({x}, {y}): scale + bias {sum:.6}, E {e:.6}"
        );
    }
}

#[test]
fn split_sum_properties() {
    let n = 64;
    for g in [GModel::Ue4, GModel::HeightCorrelated] {
        let t = split_sum(n, g, QUADRATURE, &Quiet);
        for y in 0..n {
            for x in 0..n {
                let i = (y * n + x) * 2;
                let (s, b) = (t[i], t[i + 1]);
                assert!(s >= 0.0 && b >= 0.0, "{g:?} ({x}, {y}): ({s}, {b})");
                assert!(
                    s + b <= 1.0 + 1e-4,
                    "{g:?} ({x}, {y}): scale + bias = {}",
                    s + b
                );
                // Looking straight on, V·H stays near 1 for all but the roughest lobes, so
                // the Fresnel part is small.
                if y == n - 1 {
                    assert!(
                        b < 0.05,
                        "{g:?} r = {}: bias at N·V = 1 is {b}",
                        coord(x, n)
                    );
                }
            }
            // Energy is lost as roughness grows, for views away from grazing. (At grazing
            // views the true albedo dips where α ≈ N·V and recovers — the albedo quadrature
            // shows the same dip — so no monotonicity there.)
            if coord(y, n) < 0.25 {
                continue;
            }
            for x in 1..n {
                let (a, c) = ((y * n + x - 1) * 2, (y * n + x) * 2);
                assert!(
                    t[c] + t[c + 1] <= t[a] + t[a + 1] + 1e-4,
                    "{g:?} row {y}: scale + bias rises from x = {} to {x}",
                    x - 1
                );
            }
        }
    }
    // A measured number: the centre of a white GGX r = 1 furnace sphere renders at
    // 0.305–0.308 in Blender 4.5 (docs/PHYSICS.md §12), i.e. E(N·V = 1, r = 1) with Smith
    // height-correlated G, which is scale + bias at (r, N·V) = (1, 1).
    for sampler in [Sampler::VisibleNormals, Sampler::Classic] {
        let (s, b) = split_sum_texel_sampled(1.0, 1.0, 1 << 16, GModel::HeightCorrelated, sampler);
        assert!(
            (s + b - 0.3065).abs() < 0.004,
            "{sampler:?}: E(1, 1) = {}",
            s + b
        );
    }
}

// ---- Kulla–Conty ----

#[test]
fn kulla_conty_e_and_e_avg_are_the_integrators() {
    let integrator = AlbedoIntegrator::default();
    let n = 8;
    for d in Distribution::ALL {
        for masking in [Masking::Separable, Masking::HeightCorrelated] {
            let kc = kulla_conty::kulla_conty(n, 64, d, masking, &Quiet);
            for x in 0..n {
                let glossy = Glossy::new(d, masking, Roughness::new(coord(x, n)).unwrap());
                assert_eq!(
                    kc.e_avg[x],
                    integrator.average_albedo(&glossy),
                    "{d} E_avg[{x}]"
                );
                for y in 0..n {
                    assert_eq!(
                        kc.e[y * n + x],
                        integrator.directional_albedo(&glossy, coord(y, n)),
                        "{d} E({y}, {x})"
                    );
                }
            }
            // The RGBA table carries scale, bias, ∫f_ms cos and E_avg.
            let table = kc.table();
            assert_eq!(table.channels, &["R", "G", "B", "A"]);
            for y in 0..n {
                for x in 0..n {
                    let i = y * n + x;
                    assert_eq!(table.get(x, y, 0), kc.scale[i] as f32);
                    assert_eq!(table.get(x, y, 1), kc.bias[i] as f32);
                    assert_eq!(table.get(x, y, 2), kc.fms[i] as f32);
                    assert_eq!(table.get(x, y, 3), kc.e_avg[x] as f32);
                }
            }
        }
    }
}

/// The albedo table against two independent estimators: R = E(μ, r) against the sampled
/// split-sum pair of the Kulla–Conty table (scale + bias: Monte Carlo over the same BSDF),
/// and G = E_avg(r) against 2∫E(μ)μ dμ by the midpoint rule over the R column itself.
#[test]
fn albedo_table_is_e_and_its_hemispherical_average() {
    let n = 32;
    for d in Distribution::ALL {
        for masking in [Masking::Separable, Masking::HeightCorrelated] {
            let table = kulla_conty::albedo_table(n, d, masking, &Quiet);
            assert_eq!(table.channels, &["R", "G"]);
            let kc = kulla_conty::kulla_conty(n, 4096, d, masking, &Quiet);
            let mut worst_e: f64 = 0.0;
            for x in 0..n {
                let mut midpoint = 0.0;
                for y in 0..n {
                    let e = table.get(x, y, 0) as f64;
                    assert!((0.0..=1.0).contains(&e), "{d} E({y}, {x}) = {e}");
                    let i = y * n + x;
                    worst_e = worst_e.max((e - (kc.scale[i] + kc.bias[i])).abs());
                    midpoint += 2.0 * e * coord(y, n) / n as f64;
                    assert_eq!(
                        table.get(x, y, 1),
                        table.get(x, 0, 1),
                        "G constant in a column"
                    );
                }
                let e_avg = table.get(x, 0, 1) as f64;
                // Measured: the midpoint rule over 32 rows is within 1e-4; E vs scale + bias within 5.1e-4.
                assert!(
                    (e_avg - midpoint).abs() < 5e-4,
                    "{d} {masking:?} r = {}: E_avg {e_avg} vs midpoint {midpoint}",
                    coord(x, n)
                );
            }
            assert!(
                worst_e < 1e-3,
                "{d} {masking:?}: E vs scale + bias off by {worst_e}"
            );
        }
    }
}

/// `∫ f_ms(μ, μi) cosθi dωi = 2π ∫₀¹ f_ms(μ, μi) μi dμi` by a plain midpoint rule, with
/// f_ms built from the table's E column and the integrator's E_avg as docs/PHYSICS.md §10 defines it.
fn fms_brute_force(kc: &kulla_conty::KullaConty, x: usize, y: usize) -> f64 {
    let n = kc.size;
    let column: Vec<f64> = (0..n).map(|j| kc.e[j * n + x]).collect();
    let e = |mu: f64| kulla_conty::interpolate(&column, mu).min(1.0);
    let e_avg = kc.e_avg[x];
    let m = 20_000;
    let sum: f64 = (0..m)
        .map(|k| {
            let mu_i = (k as f64 + 0.5) / m as f64;
            (1.0 - e(coord(y, n))) * (1.0 - e(mu_i)) / (std::f64::consts::PI * (1.0 - e_avg)) * mu_i
        })
        .sum();
    2.0 * std::f64::consts::PI * sum / m as f64
}

#[test]
fn kulla_conty_restores_the_missing_energy() {
    let n = 32;
    for d in Distribution::ALL {
        let kc = kulla_conty::kulla_conty(n, 4096, d, Masking::HeightCorrelated, &Quiet);
        for &(x, y) in &[
            (16, 0),
            (16, 8),
            (31, 0),
            (31, 16),
            (31, 31),
            (24, 4),
            (20, 25),
            (12, 2),
        ] {
            let i = y * n + x;
            let (e, b) = (kc.e[i], kc.fms[i]);
            // B is the integral of the lobe …
            let brute = fms_brute_force(&kc, x, y);
            assert!(
                (b - brute).abs() < 1e-6,
                "{d} ({x}, {y}): B {b}, brute force {brute}"
            );
            // … and the lobe gives back what single scattering loses.
            assert!(
                (e + b - 1.0).abs() < 2e-3,
                "{d} r = {:.3}, μ = {:.3}: E {e:.5} + ∫f_ms cos {b:.5} = {:.5}",
                coord(x, n),
                coord(y, n),
                e + b
            );
            // R + G estimates E (Cycles' sampling, 4096 samples).
            let rg = kc.scale[i] + kc.bias[i];
            assert!(
                (rg - e).abs() < 2e-3,
                "{d} ({x}, {y}): R + G {rg:.5}, E {e:.5}"
            );
        }
    }
}

#[test]
fn sampled_fms_estimator_converges_to_the_closed_form() {
    // The textbook estimator (f_ms · 4 N·L L·H / (N·H D) with GGX sampling) and the closed
    // form are the same integral; on a rough lobe the estimator is already close.
    let n = 16;
    let kc = kulla_conty::kulla_conty(n, 256, Distribution::Ggx, Masking::HeightCorrelated, &Quiet);
    for &(x, y) in &[(15, 3), (15, 12), (12, 8)] {
        let column: Vec<f64> = (0..n).map(|j| kc.e[j * n + x]).collect();
        let glossy = Glossy::new(
            Distribution::Ggx,
            Masking::HeightCorrelated,
            Roughness::new(coord(x, n)).unwrap(),
        );
        let sampled = kulla_conty::fms_sampled(&glossy, coord(y, n), 1 << 16, &column, kc.e_avg[x]);
        let b = kc.fms[y * n + x];
        assert!(
            (sampled - b).abs() < 0.02 * b.max(0.05),
            "({x}, {y}): sampled {sampled}, closed form {b}"
        );
    }
}

#[test]
fn kulla_conty_ggx_scale_bias_is_the_height_correlated_split_sum() {
    // Blender 4.x GGX with Fresnel-Schlick: the Kulla–Conty R, G are the split-sum integral
    // with Smith height-correlated G (same visible-normal points: Cycles' BSDF vs the
    // textbook formulas, both in f64).
    let n = 16;
    let mut args = LutOptions::new(Kind::KullaConty, "unused.exr");
    args.size = Some(n as u32);
    args.samples = Some(512);
    args.blender_version = Some("4.5".parse::<BlenderVersion>().unwrap());
    let kc = Spec::from_options(&args).unwrap().compute(&Quiet);
    for y in 0..n {
        for x in 0..n {
            let (s, b) = split_sum_texel_sampled(
                coord(x, n),
                coord(y, n),
                512,
                GModel::HeightCorrelated,
                Sampler::VisibleNormals,
            );
            for (c, v) in [s, b].into_iter().enumerate() {
                let a = f64::from(kc.get(x, y, c));
                assert!((a - v).abs() < 1e-6, "({x}, {y}) channel {c}: {a} vs {v}");
            }
        }
    }
}

// ---- bad input ----

fn assert_input_error(args: &LutOptions, field: Field) {
    match lut(args, &Quiet) {
        Err(Error::Input { field: named, .. }) => {
            assert_eq!(named, field, "the error names the input that was wrong")
        }
        other => panic!("{field:?}: expected an input error, got {other:?}"),
    }
    assert!(!args.out.exists(), "{field:?}: no file may be created");
}

#[test]
fn bad_input_is_refused_and_creates_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("lut.ktx2");
    for size in [0, 8193, 100_000] {
        let mut args = LutOptions::new(Kind::SplitSum, &out);
        args.size = Some(size);
        assert_input_error(&args, Field::Size);
    }
    for samples in [0, (1 << 20) + 1] {
        let mut args = LutOptions::new(Kind::KullaConty, &out);
        args.samples = Some(samples);
        assert_input_error(&args, Field::Samples);
    }
    let mut args = LutOptions::new(Kind::SplitSum, &out);
    args.distribution = Some(Distribution::Beckmann);
    assert_input_error(&args, Field::Distribution);
    let mut args = LutOptions::new(Kind::SplitSum, &out);
    args.blender_version = Some("3.4".parse().unwrap());
    assert_input_error(&args, Field::BlenderVersion);
    let mut args = LutOptions::new(Kind::KullaConty, &out);
    args.g_model = Some(GModel::Ue4);
    assert_input_error(&args, Field::GModel);
    let mut args = LutOptions::new(Kind::KullaConty, &out);
    args.method = Some(Method::Classic);
    assert_input_error(&args, Field::Method);
    // The quadrature takes no samples; the classic estimator does.
    let mut args = LutOptions::new(Kind::SplitSum, &out);
    args.samples = Some(1024);
    assert_input_error(&args, Field::Samples);
    args.method = Some(Method::Quadrature);
    assert_input_error(&args, Field::Samples);
    args.method = Some(Method::Classic);
    args.samples = Some(0);
    assert_input_error(&args, Field::Samples);
    let mut args = LutOptions::new(Kind::Albedo, &out);
    args.samples = Some(64);
    assert_input_error(&args, Field::Samples);
    let mut args = LutOptions::new(Kind::Albedo, &out);
    args.g_model = Some(GModel::HeightCorrelated);
    assert_input_error(&args, Field::GModel);
    // No --format and an extension that names none.
    let args = LutOptions::new(Kind::SplitSum, dir.path().join("lut.png"));
    assert_input_error(&args, Field::Out);
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
}

#[test]
fn unwritable_out_is_an_error_naming_the_path() {
    let dir = tempfile::tempdir().unwrap();
    let cases = [
        dir.path().join("missing-dir").join("lut.exr"),
        dir.path().to_path_buf(), // a directory
    ];
    for out in cases {
        let mut args = LutOptions::new(Kind::SplitSum, &out);
        args.size = Some(4);
        args.format = Some(Format::Exr);
        match lut(&args, &Quiet) {
            Err(e @ Error::Write { .. }) => {
                assert!(e.to_string().contains(&out.display().to_string()), "{e}");
            }
            other => panic!("{}: expected a write error, got {other:?}", out.display()),
        }
    }
    assert!(!dir.path().join("missing-dir").exists());
    assert_eq!(
        std::fs::read_dir(dir.path()).unwrap().count(),
        0,
        "no stray temporary file"
    );
}

// ---- the summary ----

#[test]
fn summary_says_what_was_written() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("brdf.dds");
    let mut args = LutOptions::new(Kind::SplitSum, &out);
    args.size = Some(16);
    let summary = lut(&args, &Quiet).unwrap();
    assert_eq!(summary.format, Format::Dds, "format from the extension");
    assert_eq!(
        (summary.width, summary.height, summary.samples),
        (16, 16, None)
    );
    let json = serde_json::to_value(&summary).unwrap();
    assert_eq!(json["kind"], "split-sum");
    assert_eq!(json["format"], "dds");
    assert_eq!(json["bits"], "16");
    assert_eq!(json["g_model"], "ue4");
    assert_eq!(json["method"], "quadrature");
    assert!(json.get("samples").is_none(), "quadrature takes no samples");
    assert_eq!(json["pixel_format"], "DXGI_FORMAT_R16G16_FLOAT");
    assert!(json["seconds"].as_f64().unwrap() >= json["compute_seconds"].as_f64().unwrap());
    assert_eq!(json["channels"][0], "R: scale");
    assert!(out.exists());

    args.method = Some(Method::Classic);
    let summary = lut(&args, &Quiet).unwrap();
    assert_eq!(
        summary.samples,
        Some(2048),
        "the classic estimator's default"
    );
    assert_eq!(summary.method, Some(Method::Classic));
}

/// `progress` is called exactly `progress_steps()` times for every kind, so a bar ends full.
#[test]
fn progress_counts_every_step() {
    use std::sync::atomic::{AtomicUsize, Ordering};
    for kind in KINDS {
        let args = small(kind, Path::new("unused.exr"), Format::Exr, Bits::Half);
        let spec = Spec::from_options(&args).unwrap();
        struct Count(AtomicUsize);
        impl Progress for Count {
            fn step(&self) {
                self.0.fetch_add(1, Ordering::Relaxed);
            }
        }
        let calls = Count(AtomicUsize::new(0));
        spec.compute(&calls);
        assert_eq!(calls.0.into_inner(), spec.progress_steps(), "{kind:?}");
    }
}

#[test]
fn anisotropic_diagonal_is_the_isotropic_albedo() {
    // Where the two widths agree (rx = ry) the lobe is isotropic: every azimuth's texel must
    // be E(μ, r), and G E_avg(r), of the isotropic integrator (another quadrature, over the
    // half vector's polar angle), at the table's grid points.
    let n = 8;
    let q = AlbedoIntegrator::default();
    for (d, v) in [
        (Distribution::Ggx, "3.4".parse::<BlenderVersion>().unwrap()),
        (Distribution::Beckmann, BlenderVersion::DEFAULT),
    ] {
        let mut args = LutOptions::new(Kind::Anisotropic, "x.exr");
        args.size = Some(n as u32);
        args.distribution = Some(d);
        args.blender_version = Some(v);
        let aniso = Spec::from_options(&args).unwrap().compute(&Quiet);
        assert_eq!((aniso.width, aniso.height), (16 * n, n * n));
        for l in 0..n {
            let r = (l as f64 / (n - 1) as f64).max(0.01);
            let g = Glossy::new(d, v.masking(), Roughness::new(r).unwrap());
            let e_avg = if r.powi(4) <= 1e-7 {
                1.0
            } else {
                q.average_albedo(&g)
            };
            for i in 0..n {
                let mu = (i as f64 / (n - 1) as f64).max(1e-3);
                // Cycles renders α² ≤ 1e-7 (r = 0.01 here) as a mirror: albedo 1.
                let e = if r.powi(4) <= 1e-7 {
                    1.0
                } else {
                    q.directional_albedo(&g, mu)
                };
                for k in 0..16 {
                    let (x, y) = (k * n + l, l * n + i);
                    let found = f64::from(aniso.get(x, y, 0));
                    assert!(
                        (found - e).abs() < 2e-4,
                        "{d} r {r} μ {mu} φ {k}: {found} vs {e}"
                    );
                    let found_avg = f64::from(aniso.get(x, y, 1));
                    assert!(
                        (found_avg - e_avg).abs() < 2e-4,
                        "{d} r {r}: E_avg {found_avg} vs {e_avg}"
                    );
                }
            }
        }
        // and off the diagonal the azimuth matters (rx = 1/7 narrow, ry = 1 wide, grazing)
        let (j, l, i) = (1, n - 1, 1);
        let along = aniso.get(j, l * n + i, 0);
        let across = aniso.get(15 * n + j, l * n + i, 0);
        assert!((along - across).abs() > 0.02, "{d}: {along} vs {across}");
    }
}

#[test]
fn anisotropic_refuses_what_blender_does_not_render() {
    let refused = |d: Distribution, v: &str| {
        let mut args = LutOptions::new(Kind::Anisotropic, "x.exr");
        args.distribution = Some(d);
        args.blender_version = Some(v.parse().unwrap());
        Spec::from_options(&args).err()
    };
    // Ashikhmin–Shirley is another model; 3.4's anisotropic Beckmann samples the wrong lobe
    // (tests/anisotropic_e2e.rs renders it).
    assert!(matches!(
        refused(Distribution::AshikhminShirley, "4.5"),
        Some(Error::Input {
            field: Field::Distribution,
            ..
        })
    ));
    assert!(matches!(
        refused(Distribution::Beckmann, "3.4"),
        Some(Error::Input {
            field: Field::BlenderVersion,
            ..
        })
    ));
    assert!(refused(Distribution::Beckmann, "3.5").is_none());
    assert!(refused(Distribution::Ggx, "3.0").is_none());
    let mut args = LutOptions::new(Kind::Anisotropic, "x.exr");
    args.size = Some(33);
    assert!(matches!(
        Spec::from_options(&args),
        Err(Error::Input {
            field: Field::Size,
            ..
        })
    ));
}

/// The glass atlas holds, at each texel, the integrator's E for that slice's index on that
/// row's side, Glass in R and Refraction in G; a matched index (slice 0) returns everything,
/// and the form follows the Blender version (3.4's two closures differ from 4.5's one).
#[test]
fn glass_texels_are_the_albedo_of_their_slice_and_side() {
    use gloffuse::measure::coat::{SLICES, slice_iors};
    use gloffuse::measure::{Dielectric, DielectricIntegrator, DielectricNode, Roughness};
    let n = 4;
    let table_of = |v: &str| {
        let mut args = LutOptions::new(Kind::Glass, "x.exr");
        args.size = Some(n as u32);
        args.blender_version = Some(v.parse().unwrap());
        args.distribution = Some(Distribution::Beckmann);
        Spec::from_options(&args).unwrap().compute(&Quiet)
    };
    let table = table_of("4.5");
    assert_eq!((table.width, table.height), (SLICES * n, 2 * n));
    let q = DielectricIntegrator::default();
    let ior = slice_iors();
    let version = "4.5".parse().unwrap();
    for (side, flip) in [(0, false), (1, true)] {
        for k in [0, 5, SLICES - 1] {
            let eta = if flip { 1.0 / ior[k] } else { ior[k] };
            for (x, y) in [(0, 0), (3, 1), (2, 3)] {
                let r = Roughness::new(coord(x, n)).unwrap();
                let texel = (k * n + x, side * n + y);
                for (c, node) in [DielectricNode::Glass, DielectricNode::Refraction]
                    .into_iter()
                    .enumerate()
                {
                    let bsdf = Dielectric::new(node, Distribution::Beckmann, r, version);
                    let e = q.directional_albedo(&bsdf, coord(y, n), eta) as f32;
                    let found = table.get(texel.0, texel.1, c);
                    assert_eq!(
                        found, e,
                        "slice {k} side {side} texel {texel:?} channel {c}"
                    );
                    if k == 0 {
                        assert_eq!(found, 1.0, "a matched index returns everything");
                    }
                }
            }
        }
    }
    let old = table_of("3.4");
    let farthest = (0..table.data.len())
        .map(|i| (table.data[i] - old.data[i]).abs())
        .fold(0.0f32, f32::max);
    assert!(farthest > 0.05, "3.4's glass is another form: {farthest}");
}

#[test]
fn glass_refuses_ashikhmin_shirley_and_oversized_atlases() {
    let mut args = LutOptions::new(Kind::Glass, "x.exr");
    args.distribution = Some(Distribution::AshikhminShirley);
    assert!(matches!(
        Spec::from_options(&args),
        Err(Error::Input {
            field: Field::Distribution,
            ..
        })
    ));
    let mut args = LutOptions::new(Kind::Glass, "x.exr");
    args.size = Some(257);
    assert!(matches!(
        Spec::from_options(&args),
        Err(Error::Input {
            field: Field::Size,
            ..
        })
    ));
}
