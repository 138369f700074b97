//! `gloffuse lut`.

use clap::Args;
use std::path::PathBuf;

use super::parse::{
    BITS, FORMATS, G_MODELS, KINDS, METHODS, one_of, parse_distribution, parse_version,
};
use gloffuse::lut::{Bits, Format, GModel, Kind, LutOptions, Method};
use gloffuse::measure::{BlenderVersion, Distribution};

/// `gloffuse lut`: write a split-sum or Kulla–Conty lookup table as EXR, DDS or KTX2.
///
/// Texel (x, y) holds roughness (x + ½)/n and N·V = (y + ½)/n; sample at uv = (roughness, N·V).
#[derive(Args, Debug, Clone, PartialEq)]
pub struct LutArgs {
    /// split-sum: GGX scale and bias (R, G); kulla-conty: scale, bias, ∫f_ms cos, E_avg (RGBA); albedo: E(μ, r), E_avg(r) (R, G); coat: A(μ, r, IOR), E(μ, r) (R, G) in 12 slices of IOR 1 to 3 side by side; anisotropic: E(μ, φ, αx, αy), E_avg(αx, αy) (R, G) in slices over the view azimuth and the bitangent width; glass: E(μ, r, η) of the Glass and Refraction BSDFs (R, G) in 12 slices of IOR 1 to 3, light entering (top row) and leaving (bottom row).
    #[arg(long, value_parser = one_of(KINDS, Kind::key), default_value = Kind::SplitSum.key())]
    pub kind: Kind,

    /// kulla-conty, albedo and coat: beckmann, ggx or ashikhmin-shirley; anisotropic and glass: beckmann or ggx [default: ggx].
    #[arg(long, short = 'd', value_parser = parse_distribution)]
    pub distribution: Option<Distribution>,

    /// kulla-conty, albedo, coat, anisotropic and glass: the Blender whose BSDF the table follows (masking: 3.0–3.4 separable, 3.5+ height-correlated; glass: 3.0–3.5 two closures, 3.6+ one) [default: 4.5].
    #[arg(long, value_parser = parse_version)]
    pub blender_version: Option<BlenderVersion>,

    /// Texels per side (per slice for coat, anisotropic and glass), 1 to 8192 (coat 1024, anisotropic 2 to 32, glass 256) [default: 512 for split-sum, 16 for anisotropic, 32 for glass, 64 otherwise].
    #[arg(long, value_name = "N")]
    pub size: Option<u32>,

    /// Hammersley samples per texel, 1 to 1048576, for kulla-conty [default: 4096] and split-sum --method classic [default: 2048]; split-sum's quadrature and albedo take none.
    #[arg(long, value_name = "N")]
    pub samples: Option<u32>,

    /// split-sum only: quadrature (deterministic, max error 5e-5) or classic (the textbook UE4 estimator verbatim, sampled) [default: quadrature].
    #[arg(long, value_parser = one_of(METHODS, Method::key))]
    pub method: Option<Method>,

    /// Bits per channel: 16 (half float) or 32 (float).
    #[arg(long, value_parser = one_of(BITS, Bits::key), default_value = Bits::Half.key())]
    pub bits: Bits,

    /// split-sum only: ue4 (Schlick-GGX, k = α/2) or height-correlated (Smith GGX) [default: ue4].
    #[arg(long, value_parser = one_of(G_MODELS, GModel::key))]
    pub g_model: Option<GModel>,

    /// exr, dds or ktx2 (KTX 2.0) [default: from the --out extension: .exr, .dds, .ktx2/.ktx].
    #[arg(long, value_parser = one_of(FORMATS, Format::key))]
    pub format: Option<Format>,

    /// The file to write (atomically: it appears complete or not at all).
    #[arg(long, short = 'o', value_name = "FILE")]
    pub out: PathBuf,

    /// Print the summary as JSON.
    #[arg(long)]
    pub json: bool,
}

impl LutArgs {
    pub fn options(&self) -> LutOptions {
        LutOptions {
            kind: self.kind,
            distribution: self.distribution,
            blender_version: self.blender_version,
            size: self.size,
            samples: self.samples,
            method: self.method,
            bits: self.bits,
            g_model: self.g_model,
            format: self.format,
            out: self.out.clone(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::{Cli, Command};
    use super::*;
    use clap::Parser;

    #[test]
    fn lut_flags_parse() {
        let cli = Cli::try_parse_from([
            "gloffuse",
            "lut",
            "--kind",
            "kulla-conty",
            "--distribution",
            "ASHIKHMIN_SHIRLEY",
            "--blender-version",
            "3.4.1",
            "--size",
            "32",
            "--samples",
            "100",
            "--bits",
            "32",
            "--format",
            "ktx",
            "--out",
            "x.ktx2",
        ])
        .unwrap();
        let Command::Lut(a) = cli.command else {
            panic!("lut parses as lut")
        };
        assert_eq!(a.kind, Kind::KullaConty);
        assert_eq!(a.distribution, Some(Distribution::AshikhminShirley));
        assert_eq!(
            (a.size, a.samples, a.bits),
            (Some(32), Some(100), Bits::Float)
        );
        assert_eq!(a.format, Some(Format::Ktx));
        let cli = Cli::try_parse_from([
            "gloffuse",
            "lut",
            "--g-model",
            "height-correlated",
            "--bits",
            "16",
            "--format",
            "dds",
            "-o",
            "y",
        ])
        .unwrap();
        let Command::Lut(a) = cli.command else {
            panic!("lut parses as lut")
        };
        assert_eq!(a.kind, Kind::SplitSum);
        assert_eq!(a.g_model, Some(GModel::HeightCorrelated));
        assert_eq!(a.format, Some(Format::Dds));
        assert!(Cli::try_parse_from(["gloffuse", "lut", "--bits", "8", "--out", "z.exr"]).is_err());
        assert!(
            Cli::try_parse_from(["gloffuse", "lut", "--kind", "split-sum"]).is_err(),
            "--out is required"
        );
    }
}
