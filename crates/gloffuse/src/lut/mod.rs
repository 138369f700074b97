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
//! Each kind is one module: [`split_sum`] (GGX's scale and bias), [`kulla_conty`] (the
//! Kulla–Conty RGBA table of Cycles' Glossy BSDF), [`albedo`] (that BSDF's E(μ, r) and
//! E_avg(r)), [`coat`] (the layered shader's coat), [`anisotropic`] (Cycles' anisotropic
//! lobe) and [`glass`] (Cycles' Glass and Refraction BSDFs). Its doc comment gives its
//! layout and channels; its `KIND` ([`KindFacts`]) is everything `lut` knows of it: its
//! key, default size and size limit, the flags it takes, its channels' meanings, how it
//! reports progress, its slices and how it is computed. [`Kind::facts`] registers it.
//!
//! # Formats
//!
//! * EXR (`exr` crate): one part, scan lines, ZIP compression (16 lines), channels R, G
//!   [, B, A] as half or float.
//! * DDS (`ddsfile` crate): DX10 header, DXGI_FORMAT_R16G16_FLOAT / R32G32_FLOAT (split-sum)
//!   or R16G16B16A16_FLOAT / R32G32B32A32_FLOAT (Kulla–Conty), one mip level.
//! * KTX 2.0 (written here, see [`ktx2`]): VK_FORMAT_R16G16_SFLOAT / R32G32_SFLOAT or
//!   R16G16B16A16_SFLOAT / R32G32B32A32_SFLOAT, one level, no supercompression.

pub mod albedo;
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
    pub const ALL: [Kind; 6] = [
        Kind::SplitSum,
        Kind::KullaConty,
        Kind::Albedo,
        Kind::Coat,
        Kind::Anisotropic,
        Kind::Glass,
    ];

    /// Everything this kind's module says of it: the one registration of a kind.
    pub fn facts(self) -> &'static KindFacts {
        match self {
            Kind::SplitSum => &split_sum::KIND,
            Kind::KullaConty => &kulla_conty::KIND,
            Kind::Albedo => &albedo::KIND,
            Kind::Coat => &coat::KIND,
            Kind::Anisotropic => &anisotropic::KIND,
            Kind::Glass => &glass::KIND,
        }
    }

    pub fn key(self) -> &'static str {
        self.facts().key
    }
}

/// What one kind of table is, written once in its module (`KIND`).
pub struct KindFacts {
    /// Its name in the options and the summary (`split-sum`, …).
    pub key: &'static str,
    /// Texels per side (per slice side for an atlas) when no size is asked for.
    pub default_size: u32,
    /// A narrower range of sizes than 1 to [`MAX_SIZE`], for an atlas of slices.
    pub size_limit: Option<SizeLimit>,
    /// What the table integrates, from the options: the kind's defaults, and its refusals
    /// of the options it does not take.
    pub bsdf: fn(&LutOptions) -> Result<Bsdf, Error>,
    /// What each stored channel holds, in order.
    pub channels: &'static [&'static str],
    /// How many times [`KindFacts::compute`] steps its progress per texel of the size.
    pub steps_per_size: usize,
    /// The index of refraction of each slice, in order (an atlas over the index).
    pub slice_iors: Option<fn() -> Vec<f64>>,
    /// The view azimuth of each column of slices, in order (an atlas over the azimuth).
    pub slice_azimuths: Option<fn() -> Vec<f64>>,
    /// The table of a validated request of this kind.
    pub compute: fn(&Spec, &dyn Progress) -> Table,
}

/// The sizes an atlas of slices accepts, and why no more.
pub struct SizeLimit {
    pub min: u32,
    pub max: u32,
    pub why: fn() -> String,
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
    /// Every kind but split-sum: the distribution [default: GGX].
    pub distribution: Option<Distribution>,
    /// Every kind but split-sum: the Blender whose BSDF the table follows [default: 4.5].
    pub blender_version: Option<BlenderVersion>,
    /// Texels per side, per slice side for an atlas [default: the kind's
    /// [`KindFacts::default_size`]].
    pub size: Option<u32>,
    /// Hammersley samples per texel: kulla-conty and split-sum with [`Method::Classic`]
    /// [default: their modules']; the kinds integrated by quadrature take none.
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
pub struct Spec {
    pub kind: Kind,
    /// Texels per side (per slice side for an atlas).
    pub size: usize,
    pub bsdf: Bsdf,
}

/// The BSDF a table integrates, and how.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Bsdf {
    /// The split-sum table's GGX: its masking term and its estimate.
    SplitSum {
        g_model: GModel,
        estimate: split_sum::Estimate,
    },
    /// A BSDF of Blender's.
    Blender(BlenderBsdf),
}

/// A BSDF as Blender `blender_version` renders it (its masking, its glass), with samples
/// per texel where the kind samples it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BlenderBsdf {
    pub distribution: Distribution,
    pub blender_version: BlenderVersion,
    pub samples: Option<u32>,
}

impl Spec {
    /// Checks the numbers and the flag combinations; errors name the flag.
    pub fn from_options(args: &LutOptions) -> Result<Spec, Error> {
        let facts = args.kind.facts();
        let size = checked_counts(args, facts)?;
        Ok(Spec {
            kind: args.kind,
            size,
            bsdf: (facts.bsdf)(args)?,
        })
    }

    /// How many times [`Spec::compute`] steps its `progress`.
    pub fn progress_steps(&self) -> usize {
        self.kind.facts().steps_per_size * self.size
    }

    /// Computes the table.
    pub fn compute(&self, progress: &dyn Progress) -> Table {
        (self.kind.facts().compute)(self, progress)
    }

    /// The BSDF of a Blender table (every kind but split-sum), for its module's `compute`.
    fn blender(&self) -> BlenderBsdf {
        match self.bsdf {
            Bsdf::Blender(bsdf) => bsdf,
            Bsdf::SplitSum { .. } => unreachable!("only split-sum's own request is its GGX"),
        }
    }
}

/// A table of Blender's BSDF: the distribution and version asked for (else GGX in the
/// default Blender), no split-sum option, and samples only where the kind samples
/// (`default_samples`).
fn blender_bsdf(args: &LutOptions, default_samples: Option<u32>) -> Result<BlenderBsdf, Error> {
    reject_split_sum_flags(args)?;
    if default_samples.is_none() {
        reject_samples(args)?;
    }
    Ok(BlenderBsdf {
        distribution: args.distribution.unwrap_or(Distribution::Ggx),
        blender_version: args.blender_version.unwrap_or(BlenderVersion::DEFAULT),
        samples: default_samples.map(|n| args.samples.unwrap_or(n)),
    })
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

/// The table's size, the kind's default where not given, and the samples asked for,
/// checked against the limits (a slice against its atlas's).
fn checked_counts(args: &LutOptions, facts: &KindFacts) -> Result<usize, Error> {
    let size = args.size.unwrap_or(facts.default_size);
    if size == 0 || size > MAX_SIZE {
        return Err(Error::input(
            Field::Size,
            size,
            format!("texels per side from 1 to {MAX_SIZE}"),
        ));
    }
    if let Some(samples) = args.samples.filter(|&n| n == 0 || n > MAX_SAMPLES) {
        return Err(Error::input(
            Field::Samples,
            samples,
            format!("samples per texel from 1 to {MAX_SAMPLES}"),
        ));
    }
    if let Some(limit) = &facts.size_limit
        && !(limit.min..=limit.max).contains(&size)
    {
        return Err(Error::input(
            Field::Size,
            size,
            Hint::new(
                format!(
                    "texels per slice side from {} to {} for {{}} {} ({})",
                    limit.min,
                    limit.max,
                    facts.key,
                    (limit.why)()
                ),
                [Field::Kind],
            ),
        ));
    }
    Ok(size as usize)
}

/// The Blender tables take their masking from the Blender version: `--g-model` and `--method` belong to split-sum.
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

/// The tables integrated by quadrature take no samples.
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
    let facts = args.kind.facts();
    Ok(LutSummary {
        path: args.out.clone(),
        kind: args.kind,
        format,
        pixel_format: pixel_format_name(format, args.bits, table.channels.len()),
        bits: args.bits,
        width: table.width,
        height: table.height,
        channels: facts.channels.iter().map(|c| c.to_string()).collect(),
        samples: settings.samples,
        g_model: settings.g_model,
        method: settings.method,
        distribution: settings.distribution,
        blender_version: settings.blender_version,
        ior: facts.slice_iors.map(|iors| iors()),
        azimuths: facts.slice_azimuths.map(|azimuths| azimuths()),
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
        match spec.bsdf {
            Bsdf::SplitSum { g_model, estimate } => {
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
            Bsdf::Blender(BlenderBsdf {
                distribution,
                blender_version,
                samples,
            }) => Settings {
                samples,
                g_model: None,
                method: None,
                distribution: Some(distribution),
                blender_version: Some(blender_version.to_string()),
            },
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
