//! `gloffuse albedo`.

use clap::Args;
use std::path::PathBuf;

use super::parse::{parse_distribution, parse_model, parse_mu, parse_roughness, parse_version};
use gloffuse::albedo::AlbedoOptions;
use gloffuse::measure::brdf::{Model, ModelParams};
use gloffuse::measure::{BlenderVersion, Distribution, Roughness};

#[derive(Args, Debug)]
pub struct AlbedoArgs {
    /// beckmann, ggx or ashikhmin-shirley (case-insensitive; BECKMANN, GGX, ASHIKHMIN_SHIRLEY work too).
    #[arg(long, short = 'd', value_parser = parse_distribution, required_unless_present = "model")]
    pub distribution: Option<Distribution>,

    /// A classic BRDF instead of Blender's Glossy: lambert, phong (normalised modified Phong),
    /// ward (anisotropic), cook-torrance (Beckmann D, Schlick Fresnel), fresnel-blend
    /// (Ashikhmin–Shirley's diffuse term). Parameters: --rho, --rs, --exponent, --alpha-x, --alpha-y.
    #[arg(long, value_parser = parse_model, conflicts_with_all = ["distribution", "roughness", "table"])]
    pub model: Option<Model>,

    /// --model: reflectance ρ (Lambert), ρs (Phong, Ward), f0 (Cook–Torrance) or Rd (Fresnel blend).
    #[arg(long, default_value_t = ModelParams::default().rho, allow_hyphen_values = true)]
    pub rho: f64,

    /// --model fresnel-blend: specular reflectance Rs at normal incidence.
    #[arg(long, default_value_t = ModelParams::default().rs, allow_hyphen_values = true)]
    pub rs: f64,

    /// --model phong: the exponent n.
    #[arg(long, default_value_t = ModelParams::default().exponent, allow_hyphen_values = true)]
    pub exponent: f64,

    /// --model ward: αx (along the tangent); --model cook-torrance: α.
    #[arg(long, default_value_t = ModelParams::default().alpha_x, allow_hyphen_values = true)]
    pub alpha_x: f64,

    /// --model ward: αy (along the bitangent).
    #[arg(long, default_value_t = ModelParams::default().alpha_y, allow_hyphen_values = true)]
    pub alpha_y: f64,

    /// The Glossy node's Roughness, 0 to 1 (Cycles uses alpha = r²).
    #[arg(long, short = 'r', value_parser = parse_roughness, allow_hyphen_values = true)]
    pub roughness: Option<Roughness>,

    /// View cosine μ = N·V in (0, 1]; 1 looks straight at the surface (a sphere's centre).
    #[arg(long, default_value = "1", value_parser = parse_mu, allow_hyphen_values = true)]
    pub mu: f64,

    /// Blender version whose masking to model: 3.0–3.4 separable, 3.5 and later height-correlated.
    #[arg(long, default_value_t = BlenderVersion::DEFAULT, value_parser = parse_version)]
    pub blender_version: BlenderVersion,

    /// Write a CSV grid instead: roughness j/(N−1) for j < N, μ = (i + ½)/N for i < N.
    #[arg(long, value_name = "FILE.csv")]
    pub table: Option<PathBuf>,

    /// Grid size N for --table.
    #[arg(long, default_value_t = 64, value_parser = clap::value_parser!(u32).range(2..=4096))]
    pub grid: u32,

    /// Print JSON instead of text.
    #[arg(long)]
    pub json: bool,
}

impl AlbedoArgs {
    pub fn options(&self) -> AlbedoOptions {
        AlbedoOptions {
            distribution: self.distribution,
            model: self.model,
            params: ModelParams {
                rho: self.rho,
                rs: self.rs,
                exponent: self.exponent,
                alpha_x: self.alpha_x,
                alpha_y: self.alpha_y,
            },
            roughness: self.roughness,
            mu: self.mu,
            blender_version: self.blender_version,
            table: self.table.clone(),
            grid: self.grid as usize,
        }
    }
}
