//! Lookup tables for real-time renderers (`docs/PHYSICS.md` §10): the split-sum LUT and the
//! Kulla–Conty energy-compensation LUT, written as EXR, DDS or KTX2 textures.
//!
//! # Layout (every kind, every format)
//!
//! An n × n texture, row-major, **first row first**: texel (x, y) holds roughness
//! `r = (x + ½)/n` and view cosine `N·V = (y + ½)/n` (pixel centres), so a shader samples
//! it at `uv = (roughness, N·V)` with the file's rows uploaded in order (row 0 at v = 0, the
//! top of the image in an EXR viewer). Values are linear floats (16-bit half or 32-bit).
//!
//! # Kinds
//!
//! * [`Kind::SplitSum`], 2 channels: **R = scale, G = bias**, the classic GGX "BRDF
//!   generator" (see [`split_sum`]); at run time `specular = F0 · scale + bias`. By default
//!   computed by deterministic quadrature (no samples): 512² within 2.2e-5 of the converged
//!   table (`cargo bench --bench lut`); `--method classic` is the textbook estimator
//!   verbatim, with `--samples` (1e-2 off near grazing at 1024 samples).
//! * [`Kind::Albedo`], 2 channels, for the same Glossy BSDF: **R = E(μ, r)** and
//!   **G = E_avg(r)** (constant along each column), both by the deterministic quadrature of
//!   [`crate::measure::AlbedoIntegrator`] (no samples; max error 3.2e-5): the two
//!   Kulla–Conty tables a renderer needs to build its own compensation.
//! * [`Kind::KullaConty`], 4 channels, for the Glossy BSDF that Cycles evaluates (chosen by
//!   `--distribution` and `--blender-version`; see [`kulla_conty`]):
//!   **R = scale, G = bias** (the same split-sum pair, integrated over Cycles' BSDF, so
//!   `R + G ≈ E(μ, r)`), **B = ∫ f_ms(μ, μi) cosθi dωi** (the multiple-scattering lobe
//!   `f_ms = (1 − E(μ))(1 − E(μi)) / (π (1 − E_avg))`, integrated in closed form; it is
//!   `≈ 1 − E(μ)`), and **A = E_avg(r)** (constant along each column) for the Fresnel term
//!   `F_avg E_avg / (1 − F_avg (1 − E_avg))` that scales B under a coloured Fresnel.
//!   `E(μ, r)` itself (Cycles-exact, from [`crate::measure::AlbedoIntegrator`]) is in
//!   [`kulla_conty::KullaConty::e`].
//! * [`Kind::Coat`], 2 channels, the coat of the layered shader (see [`coat`]): 12 slices of
//!   n × n side by side (an atlas 12n wide), slice k for index of refraction `ior[k]`
//!   (listed in the summary): **R = A(μ, r, η)**, the albedo of a dielectric microfacet
//!   coat with its lost energy given back, **G = E(μ, r)**. Quadrature, no samples.
//!
//! * [`Kind::Anisotropic`], 2 channels, Cycles' anisotropic GGX or Beckmann lobe (see
//!   [`anisotropic`]): an atlas of 16 view azimuths side by side × n bitangent widths
//!   stacked, each slice n × n over (tangent width, N·V) at grid points, not pixel centres:
//!   **R = E(μ, φ, αx, αy)**, **G = E_avg(αx, αy)**. Quadrature, no samples.
//! * [`Kind::Glass`], 2 channels, Cycles' Glass and Refraction BSDFs (see [`glass`]): 12
//!   slices of n × n side by side over the index of refraction, light entering (η = IOR) in
//!   the top row and leaving (η = 1/IOR) in the bottom one: **R = E(μ, r, η)** of the Glass
//!   BSDF, **G = E(μ, r, η)** of the Refraction BSDF. Quadrature, no samples.
//!
//! # Formats
//!
//! * EXR (`exr` crate): one part, scan lines, ZIP compression (16 lines), channels R, G
//!   [, B, A] as half or float.
//! * DDS (`ddsfile` crate): DX10 header, DXGI_FORMAT_R16G16_FLOAT / R32G32_FLOAT (split-sum)
//!   or R16G16B16A16_FLOAT / R32G32B32A32_FLOAT (Kulla–Conty), one mip level.
//! * KTX 2.0 (written here, see [`ktx2`]): VK_FORMAT_R16G16_SFLOAT / R32G32_SFLOAT or
//!   R16G16B16A16_SFLOAT / R32G32B32A32_SFLOAT, one level, no supercompression.

pub mod anisotropic;
pub mod coat;
pub mod dds;
pub mod glass;
pub mod ktx2;
pub mod kulla_conty;
pub mod openexr;
pub mod split_sum;

use std::path::{Path, PathBuf};
use std::time::Instant;

use crate::error::{Error, Field, Hint};
use crate::measure::{BlenderVersion, Distribution};
use crate::output::{check_destination, write_output};
use crate::progress::Progress;

/// The largest `--size` accepted: 8192² texels of RGBA32F is already 1 GiB.
pub const MAX_SIZE: u32 = 8192;
/// The largest `--samples` accepted per texel.
pub const MAX_SAMPLES: u32 = 1 << 20;

/// Which table to compute.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Kind {
    /// GGX split-sum (R = scale, G = bias).
    SplitSum,
    /// Kulla–Conty for a Cycles Glossy BSDF (R = scale, G = bias, B = ∫f_ms cos, A = E_avg).
    KullaConty,
    /// Kulla–Conty's albedo tables for a Cycles Glossy BSDF (R = E(μ, r), G = E_avg(r)).
    Albedo,
    /// The layered shader's coat: slices over the index of refraction (R = A(μ, r, η),
    /// G = E(μ, r)).
    Coat,
    /// Cycles' anisotropic lobe: slices over the view azimuth and the bitangent width
    /// (R = E(μ, φ, αx, αy), G = E_avg(αx, αy)).
    Anisotropic,
    /// Cycles' Glass and Refraction BSDFs: slices over the index, entering and leaving
    /// (R = E(μ, r, η) of Glass, G = of Refraction).
    Glass,
}

impl Kind {
    pub fn key(self) -> &'static str {
        match self {
            Kind::SplitSum => "split-sum",
            Kind::KullaConty => "kulla-conty",
            Kind::Albedo => "albedo",
            Kind::Coat => "coat",
            Kind::Anisotropic => "anisotropic",
            Kind::Glass => "glass",
        }
    }
}

/// The masking–shadowing term of the split-sum table.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum GModel {
    /// Separable Schlick-GGX with k = α/2 (Karis' UE4 table).
    Ue4,
    /// Smith GGX height-correlated, G2 = 1/(1 + Λ(V) + Λ(L)) (Cycles 3.5+, Filament).
    HeightCorrelated,
}

impl GModel {
    pub fn key(self) -> &'static str {
        match self {
            GModel::Ue4 => "ue4",
            GModel::HeightCorrelated => "height-correlated",
        }
    }
}

/// How the split-sum integral is computed (both compute the same integral; see
/// [`split_sum`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Method {
    /// Deterministic Gauss–Legendre quadrature cut at the horizon of L: within 5e-5.
    Quadrature,
    /// The textbook (UE4) estimator to the letter: H ~ D·N·H, N Hammersley samples; up to
    /// 1e-2 off near grazing at 1024.
    Classic,
}

impl Method {
    pub fn key(self) -> &'static str {
        match self {
            Method::Quadrature => "quadrature",
            Method::Classic => "classic",
        }
    }
}

/// The container written.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Format {
    /// OpenEXR, ZIP-compressed scan lines.
    Exr,
    /// DirectDraw Surface with a DX10 header.
    Dds,
    /// KTX 2.0 (not KTX 1).
    #[serde(rename = "ktx2")]
    Ktx,
}

impl Format {
    /// The format a file name's extension implies: `.exr`, `.dds`, `.ktx2` / `.ktx`.
    pub fn from_path(path: &Path) -> Option<Format> {
        let ext = path.extension()?.to_str()?.to_ascii_lowercase();
        match ext.as_str() {
            "exr" => Some(Format::Exr),
            "dds" => Some(Format::Dds),
            "ktx2" | "ktx" => Some(Format::Ktx),
            _ => None,
        }
    }

    pub fn key(self) -> &'static str {
        match self {
            Format::Exr => "exr",
            Format::Dds => "dds",
            Format::Ktx => "ktx2",
        }
    }
}

/// Bits per channel of the stored floats.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub enum Bits {
    /// IEEE half floats (what GPUs sample fastest; rounding error ≤ 2.5e-4 below 1).
    #[serde(rename = "16")]
    Half,
    /// IEEE single floats (exactly the computed values).
    #[serde(rename = "32")]
    Float,
}

impl Bits {
    pub fn count(self) -> u32 {
        match self {
            Bits::Half => 16,
            Bits::Float => 32,
        }
    }

    /// The command-line spelling: `16` or `32`.
    pub fn key(self) -> &'static str {
        match self {
            Bits::Half => "16",
            Bits::Float => "32",
        }
    }
}

/// What `gloffuse lut` computes and writes. `None` means the kind's default (see
/// [`Spec::from_options`], which also refuses combinations that make no sense).
#[derive(Clone, Debug, PartialEq)]
pub struct LutOptions {
    pub kind: Kind,
    /// kulla-conty and albedo: the distribution [default: GGX].
    pub distribution: Option<Distribution>,
    /// kulla-conty and albedo: the Blender whose masking the BSDF follows [default: 4.5].
    pub blender_version: Option<BlenderVersion>,
    /// Texels per side [default: 512 split-sum, 64 otherwise].
    pub size: Option<u32>,
    /// Hammersley samples per texel: kulla-conty [default: 4096] and split-sum with
    /// [`Method::Classic`] [default: 2048]; the quadrature and albedo take none.
    pub samples: Option<u32>,
    /// split-sum only [default: quadrature].
    pub method: Option<Method>,
    pub bits: Bits,
    /// split-sum only [default: ue4].
    pub g_model: Option<GModel>,
    /// [default: from the extension of `out`].
    pub format: Option<Format>,
    /// The file to write (atomically: it appears complete or not at all).
    pub out: PathBuf,
}

impl LutOptions {
    /// Options with every default, writing to `out`.
    pub fn new(kind: Kind, out: impl Into<PathBuf>) -> Self {
        LutOptions {
            kind,
            distribution: None,
            blender_version: None,
            size: None,
            samples: None,
            method: None,
            bits: Bits::Half,
            g_model: None,
            format: None,
            out: out.into(),
        }
    }
}

/// A computed table: `width × height` texels, row-major, `channels.len()` interleaved f32
/// values per texel.
#[derive(Clone, Debug, PartialEq)]
pub struct Table {
    pub width: usize,
    pub height: usize,
    /// Channel names as stored: `R`, `G`[, `B`, `A`].
    pub channels: &'static [&'static str],
    pub data: Vec<f32>,
}

impl Table {
    /// Texel (x, y), channel c.
    pub fn get(&self, x: usize, y: usize, c: usize) -> f32 {
        self.data[(y * self.width + x) * self.channels.len() + c]
    }

    /// The texels as a GPU uploads them: row-major, channels interleaved, little-endian
    /// IEEE half (rounded to nearest even) or single floats.
    pub fn texel_bytes(&self, bits: Bits) -> Vec<u8> {
        match bits {
            Bits::Half => self
                .data
                .iter()
                .flat_map(|&v| half::f16::from_f32(v).to_le_bytes())
                .collect(),
            Bits::Float => self.data.iter().flat_map(|&v| v.to_le_bytes()).collect(),
        }
    }
}

/// What a validated request computes (parse, don't validate: built once from [`LutOptions`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Spec {
    SplitSum {
        size: usize,
        g_model: GModel,
        estimate: split_sum::Estimate,
    },
    KullaConty {
        size: usize,
        samples: u32,
        distribution: Distribution,
        blender_version: BlenderVersion,
    },
    Albedo {
        size: usize,
        distribution: Distribution,
        blender_version: BlenderVersion,
    },
    Coat {
        size: usize,
        distribution: Distribution,
        blender_version: BlenderVersion,
    },
    Anisotropic {
        size: usize,
        distribution: Distribution,
        blender_version: BlenderVersion,
    },
    Glass {
        size: usize,
        distribution: Distribution,
        blender_version: BlenderVersion,
    },
}

impl Spec {
    /// Checks the numbers and the flag combinations; errors name the flag.
    pub fn from_options(args: &LutOptions) -> Result<Spec, Error> {
        let (size, samples) = checked_counts(args)?;
        let distribution = args.distribution.unwrap_or(Distribution::Ggx);
        let blender_version = args.blender_version.unwrap_or(BlenderVersion::DEFAULT);
        match args.kind {
            Kind::SplitSum => split_sum_spec(args, size, samples),
            Kind::KullaConty => {
                reject_split_sum_flags(args)?;
                Ok(Spec::KullaConty {
                    size,
                    samples,
                    distribution,
                    blender_version,
                })
            }
            Kind::Albedo => {
                reject_split_sum_flags(args)?;
                reject_samples(args)?;
                Ok(Spec::Albedo {
                    size,
                    distribution,
                    blender_version,
                })
            }
            Kind::Coat => {
                reject_split_sum_flags(args)?;
                reject_samples(args)?;
                Ok(Spec::Coat {
                    size,
                    distribution,
                    blender_version,
                })
            }
            Kind::Anisotropic => {
                reject_split_sum_flags(args)?;
                reject_samples(args)?;
                microfacet_only(
                    distribution,
                    args.kind,
                    "the table covers the two microfacet distributions",
                )?;
                if !blender_version.renders_anisotropic(distribution) {
                    return Err(Error::input(
                        Field::BlenderVersion,
                        blender_version,
                        Hint::new(
                            "3.5 or later with {} beckmann {} anisotropic (Blender 3.0–3.4 sample an isotropic lobe for anisotropic Beckmann, so they do not render the lobe this table describes; GGX is right in every version)",
                            [Field::Distribution, Field::Kind],
                        ),
                    ));
                }
                Ok(Spec::Anisotropic {
                    size,
                    distribution,
                    blender_version,
                })
            }
            Kind::Glass => {
                reject_split_sum_flags(args)?;
                reject_samples(args)?;
                microfacet_only(
                    distribution,
                    args.kind,
                    "Blender's Glass and Refraction BSDFs have no Ashikhmin-Shirley",
                )?;
                Ok(Spec::Glass {
                    size,
                    distribution,
                    blender_version,
                })
            }
        }
    }

    /// How many times [`Spec::compute`] steps its `progress`.
    pub fn progress_steps(&self) -> usize {
        match *self {
            Spec::SplitSum { size, .. }
            | Spec::Albedo { size, .. }
            | Spec::Coat { size, .. }
            | Spec::Glass { size, .. } => size,
            Spec::KullaConty { size, .. } | Spec::Anisotropic { size, .. } => 2 * size,
        }
    }

    /// Computes the table.
    pub fn compute(&self, progress: &dyn Progress) -> Table {
        match *self {
            Spec::SplitSum {
                size,
                g_model,
                estimate,
            } => Table {
                width: size,
                height: size,
                channels: &["R", "G"],
                data: split_sum::split_sum(size, g_model, estimate, progress),
            },
            Spec::KullaConty {
                size,
                samples,
                distribution,
                blender_version,
            } => kulla_conty::kulla_conty(
                size,
                samples,
                distribution,
                blender_version.masking(),
                progress,
            )
            .table(),
            Spec::Albedo {
                size,
                distribution,
                blender_version,
            } => kulla_conty::albedo_table(size, distribution, blender_version.masking(), progress),
            Spec::Coat {
                size,
                distribution,
                blender_version,
            } => coat::coat_table(size, distribution, blender_version.masking(), progress),
            Spec::Anisotropic {
                size,
                distribution,
                blender_version,
            } => anisotropic::anisotropic_table(
                size,
                distribution,
                blender_version.masking(),
                progress,
            ),
            Spec::Glass {
                size,
                distribution,
                blender_version,
            } => glass::glass_table(size, distribution, blender_version, progress),
        }
    }
}

/// GGX or Beckmann: the kinds whose table covers only the two microfacet distributions.
fn microfacet_only(distribution: Distribution, kind: Kind, why: &str) -> Result<(), Error> {
    if distribution != Distribution::AshikhminShirley {
        return Ok(());
    }
    Err(Error::input(
        Field::Distribution,
        distribution.key(),
        Hint::new(
            format!("ggx or beckmann with {{}} {} ({why})", kind.key()),
            [Field::Kind],
        ),
    ))
}

/// The table's size and samples per texel, the kind's defaults where not given, checked
/// against the limits (a coat slice against its atlas's).
fn checked_counts(args: &LutOptions) -> Result<(usize, u32), Error> {
    let (default_size, default_samples) = match args.kind {
        Kind::SplitSum => (512, 2048),
        Kind::KullaConty => (64, 4096),
        Kind::Albedo | Kind::Coat => (64, 1),
        Kind::Anisotropic => (16, 1),
        Kind::Glass => (32, 1),
    };
    let size = args.size.unwrap_or(default_size);
    let samples = args.samples.unwrap_or(default_samples);
    if size == 0 || size > MAX_SIZE {
        return Err(Error::input(
            Field::Size,
            size,
            format!("texels per side from 1 to {MAX_SIZE}"),
        ));
    }
    if samples == 0 || samples > MAX_SAMPLES {
        return Err(Error::input(
            Field::Samples,
            samples,
            format!("samples per texel from 1 to {MAX_SAMPLES}"),
        ));
    }
    if args.kind == Kind::Coat && size > coat::MAX_SIZE {
        return Err(Error::input(
            Field::Size,
            size,
            Hint::new(
                format!(
                    "texels per slice side from 1 to {} for {{}} coat (its atlas is {} slices wide)",
                    coat::MAX_SIZE,
                    crate::measure::coat::SLICES
                ),
                [Field::Kind],
            ),
        ));
    }
    if args.kind == Kind::Glass && size > glass::MAX_SIZE {
        return Err(Error::input(
            Field::Size,
            size,
            Hint::new(
                format!(
                    "texels per slice side from 1 to {} for {{}} glass (its atlas is {} slices wide and two high)",
                    glass::MAX_SIZE,
                    crate::measure::coat::SLICES
                ),
                [Field::Kind],
            ),
        ));
    }
    if args.kind == Kind::Anisotropic && !(2..=anisotropic::MAX_SIZE).contains(&size) {
        return Err(Error::input(
            Field::Size,
            size,
            Hint::new(
                format!(
                    "texels per slice side from 2 to {} for {{}} anisotropic (its atlas holds {} × size slices of size² albedos, each a 9,216-point quadrature)",
                    anisotropic::MAX_SIZE,
                    anisotropic::AZIMUTHS
                ),
                [Field::Kind],
            ),
        ));
    }
    Ok((size as usize, samples))
}

/// The split-sum table: GGX, no Blender version, and samples only for the classic method.
fn split_sum_spec(args: &LutOptions, size: usize, samples: u32) -> Result<Spec, Error> {
    if let Some(d) = args.distribution.filter(|&d| d != Distribution::Ggx) {
        return Err(Error::input(
            Field::Distribution,
            d.key(),
            Hint::new(
                "ggx or nothing: the split-sum table is GGX by definition (use {} kulla-conty for Cycles' Beckmann or Ashikhmin-Shirley)",
                [Field::Kind],
            ),
        ));
    }
    if let Some(v) = args.blender_version {
        return Err(Error::input(
            Field::BlenderVersion,
            v,
            Hint::new(
                "nothing with {} split-sum (choose its masking with {}; {} applies to kulla-conty)",
                [Field::Kind, Field::GModel, Field::BlenderVersion],
            ),
        ));
    }
    let estimate = match args.method.unwrap_or(Method::Quadrature) {
        Method::Quadrature => {
            if let Some(n) = args.samples {
                return Err(Error::input(
                    Field::Samples,
                    n,
                    Hint::new(
                        "nothing with {} split-sum's default {} quadrature (it is deterministic quadrature, not sampled; {} applies to {} classic)",
                        [Field::Kind, Field::Method, Field::Samples, Field::Method],
                    ),
                ));
            }
            split_sum::Estimate::Quadrature(split_sum::Rule::default())
        }
        Method::Classic => split_sum::Estimate::Classic { samples },
    };
    Ok(Spec::SplitSum {
        size,
        g_model: args.g_model.unwrap_or(GModel::Ue4),
        estimate,
    })
}

/// The Blender tables (kulla-conty, albedo, coat) take their masking from the Blender
/// version: `--g-model` and `--method` belong to split-sum.
fn reject_split_sum_flags(args: &LutOptions) -> Result<(), Error> {
    let kind = args.kind.key();
    if let Some(g) = args.g_model {
        return Err(Error::input(
            Field::GModel,
            g.key(),
            Hint::new(
                format!(
                    "nothing with {{}} {kind} (its masking follows {{}}; {{}} applies to split-sum)"
                ),
                [Field::Kind, Field::BlenderVersion, Field::GModel],
            ),
        ));
    }
    if let Some(m) = args.method {
        return Err(Error::input(
            Field::Method,
            m.key(),
            Hint::new(
                format!("nothing with {{}} {kind} ({{}} applies to split-sum)"),
                [Field::Kind, Field::Method],
            ),
        ));
    }
    Ok(())
}

/// Albedo and coat are integrated by quadrature: no samples.
fn reject_samples(args: &LutOptions) -> Result<(), Error> {
    match args.samples {
        Some(n) => Err(Error::input(
            Field::Samples,
            n,
            Hint::new(
                format!(
                    "nothing with {{}} {} (it is integrated by deterministic quadrature, not sampled)",
                    args.kind.key()
                ),
                [Field::Kind],
            ),
        )),
        None => Ok(()),
    }
}

/// Encodes a table in memory as a file of the given format and bit depth (an error is the
/// encoder's message; it does not happen for tables that [`Spec::compute`] makes).
pub fn encode(table: &Table, format: Format, bits: Bits) -> Result<Vec<u8>, String> {
    match format {
        Format::Exr => openexr::encode(table, bits),
        Format::Dds => dds::encode(table, bits),
        Format::Ktx => Ok(ktx2::encode(table, bits)),
    }
}

/// What [`lut`] wrote.
#[derive(Clone, Debug, serde::Serialize)]
pub struct LutSummary {
    pub path: PathBuf,
    pub kind: Kind,
    pub format: Format,
    /// The GPU format name: `VK_FORMAT_…` (KTX2), `DXGI_FORMAT_…` (DDS) or `half`/`float` (EXR).
    pub pixel_format: String,
    pub bits: Bits,
    pub width: usize,
    pub height: usize,
    /// What each stored channel holds, in order.
    pub channels: Vec<String>,
    /// Samples per texel (none for quadrature: `albedo` and split-sum's default method).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub samples: Option<u32>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub g_model: Option<GModel>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub method: Option<Method>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub distribution: Option<Distribution>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub blender_version: Option<String>,
    /// coat: the index of refraction of each slice, in order.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub ior: Option<Vec<f64>>,
    /// anisotropic: the view azimuth (radians from the tangent) of each column of slices.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub azimuths: Option<Vec<f64>>,
    /// Size of the written file.
    pub bytes: usize,
    /// Wall-clock seconds spent computing the table (excluding encoding and writing).
    pub compute_seconds: f64,
    /// Wall-clock seconds for the whole call.
    pub seconds: f64,
}

/// Computes the table `args` asks for, encodes it in memory and writes it atomically to
/// `args.out` (nothing is created on any error); `progress` steps per row or column.
pub fn lut(args: &LutOptions, progress: &dyn Progress) -> Result<LutSummary, Error> {
    let start = Instant::now();
    let spec = Spec::from_options(args)?;
    let format = output_format(args)?;
    // A bad destination fails before minutes of computing, not after.
    check_destination(&args.out)?;
    let t = Instant::now();
    progress.begin(
        &format!("computing the {} table", args.kind.key()),
        spec.progress_steps() as u64,
    );
    let table = spec.compute(progress);
    progress.end();
    let compute_seconds = t.elapsed().as_secs_f64();
    let bytes = encode(&table, format, args.bits).map_err(|message| Error::Write {
        path: args.out.clone(),
        message: format!("cannot encode the table as {}: {message}", format.key()),
    })?;
    write_output(&args.out, &bytes)?;
    let settings = Settings::of(&spec);
    Ok(LutSummary {
        path: args.out.clone(),
        kind: args.kind,
        format,
        pixel_format: pixel_format_name(format, args.bits, table.channels.len()),
        bits: args.bits,
        width: table.width,
        height: table.height,
        channels: spec
            .channel_meanings()
            .iter()
            .map(|c| c.to_string())
            .collect(),
        samples: settings.samples,
        g_model: settings.g_model,
        method: settings.method,
        distribution: settings.distribution,
        blender_version: settings.blender_version,
        ior: matches!(spec, Spec::Coat { .. } | Spec::Glass { .. }).then(coat::ior),
        azimuths: matches!(spec, Spec::Anisotropic { .. }).then(anisotropic::azimuths),
        bytes: bytes.len(),
        compute_seconds,
        seconds: start.elapsed().as_secs_f64(),
    })
}

/// The format asked for, else the one `args.out`'s extension names.
fn output_format(args: &LutOptions) -> Result<Format, Error> {
    match args.format {
        Some(f) => Ok(f),
        None => Format::from_path(&args.out).ok_or_else(|| {
            Error::input(
                Field::Out,
                args.out.display(),
                Hint::new(
                    "a file name ending in .exr, .dds or .ktx2 (or give {} exr|dds|ktx)",
                    [Field::Format],
                ),
            )
        }),
    }
}

/// The settings of a [`Spec`] a [`LutSummary`] reports, each where the kind has it.
struct Settings {
    samples: Option<u32>,
    g_model: Option<GModel>,
    method: Option<Method>,
    distribution: Option<Distribution>,
    blender_version: Option<String>,
}

impl Settings {
    fn of(spec: &Spec) -> Self {
        match *spec {
            Spec::SplitSum {
                g_model, estimate, ..
            } => {
                let (samples, method) = match estimate {
                    split_sum::Estimate::Classic { samples } => (Some(samples), Method::Classic),
                    split_sum::Estimate::Quadrature(_) => (None, Method::Quadrature),
                };
                Settings {
                    samples,
                    g_model: Some(g_model),
                    method: Some(method),
                    distribution: None,
                    blender_version: None,
                }
            }
            Spec::KullaConty {
                samples,
                distribution,
                blender_version,
                ..
            } => Settings {
                samples: Some(samples),
                ..Settings::blender(distribution, blender_version)
            },
            Spec::Albedo {
                distribution,
                blender_version,
                ..
            }
            | Spec::Coat {
                distribution,
                blender_version,
                ..
            }
            | Spec::Anisotropic {
                distribution,
                blender_version,
                ..
            }
            | Spec::Glass {
                distribution,
                blender_version,
                ..
            } => Settings::blender(distribution, blender_version),
        }
    }

    /// A table of Blender's own distribution and masking, not sampled.
    fn blender(distribution: Distribution, blender_version: BlenderVersion) -> Self {
        Settings {
            samples: None,
            g_model: None,
            method: None,
            distribution: Some(distribution),
            blender_version: Some(blender_version.to_string()),
        }
    }
}

impl Spec {
    /// What each stored channel holds, in order.
    fn channel_meanings(&self) -> &'static [&'static str] {
        match self {
            Spec::SplitSum { .. } => &["R: scale", "G: bias"],
            Spec::KullaConty { .. } => &[
                "R: scale",
                "G: bias",
                "B: integral of f_ms cos (≈ 1 − E)",
                "A: E_avg(r)",
            ],
            Spec::Coat { .. } => &["R: A(μ, r, IOR of the slice)", "G: E(μ, r)"],
            Spec::Albedo { .. } => &["R: E(μ, r)", "G: E_avg(r)"],
            Spec::Anisotropic { .. } => &[
                "R: E(N·V, φ of the slice's column, αx = rx², αy = ry² of the slice's row)",
                "G: E_avg(αx, αy)",
            ],
            Spec::Glass { .. } => &[
                "R: E(μ, r, η) of the Glass BSDF, η = IOR of the slice (top row) or 1/IOR (bottom row)",
                "G: E(μ, r, η) of the Refraction BSDF",
            ],
        }
    }
}

fn pixel_format_name(format: Format, bits: Bits, channels: usize) -> String {
    match format {
        Format::Exr => match bits {
            Bits::Half => "half".into(),
            Bits::Float => "float".into(),
        },
        Format::Dds => dds::dxgi_format(bits, channels)
            .map(|f| format!("DXGI_FORMAT_{f:?}").to_ascii_uppercase())
            .unwrap_or_default(),
        Format::Ktx => ktx2::VkFormat::of(bits, channels).name().into(),
    }
}
