//! `gloffuse generate`.

use clap::Args;
use std::path::PathBuf;

use super::blender::BlenderArgs;
use super::parse::{COLOR_MODELS, ENGINES, MODES, one_of};
use gloffuse::generate::{ColorModel, GenerateOptions, Mode};
use gloffuse::measure::Engine;

pub(super) const GENERATE_EXAMPLES: &str = "\
Examples:
  gloffuse generate --extension gloffuse.zip     an extension to install in Blender 4.2+
  gloffuse generate --addon gloffuse-addon.zip --blender /usr/bin/blender
                                                 a classic add-on for Blender 3.4 to 4.1
  gloffuse generate --blend lib/gloffuse.blend --mode roughness,view
                                                 a library .blend with the view groups too
  gloffuse generate --blend lib/gloffuse.blend --mode layered
                                                 the glossy-over-diffuse Gloffuse Layered groups
  gloffuse generate --into scene.blend           update the groups in your file, in place
  gloffuse generate --script gloffuse.py         a script for Blender's Text Editor";

#[derive(Args, Debug)]
pub struct GenerateArgs {
    /// A preset (seed, blender-3, blender-4) or a coefficients file [default: the preset of
    /// the Blender the groups are built in: blender-3 for 3.0–3.4, blender-4 for 3.5 and
    /// later; a script carries both and picks when it runs].
    #[arg(long, value_name = "PRESET|FILE")]
    pub coefficients: Option<String>,

    /// Write the generated Python script here (no Blender needed). Run it in Blender's
    /// Text Editor, or `blender -b --python FILE -- --save OUT.blend`.
    #[arg(long, value_name = "OUT.py")]
    pub script: Option<PathBuf>,

    /// Write a new .blend library holding the groups, as assets with previews, and its
    /// catalog file beside it (blender_assets.cats.txt, merged into an existing one): mark
    /// the folder as an asset library in Preferences ▸ File Paths, or File ▸ Append.
    #[arg(long, value_name = "OUT.blend", conflicts_with = "into")]
    pub blend: Option<PathBuf>,

    /// Let --blend replace an existing .blend that is not a gloffuse library (a scene, or a
    /// library made before gloffuse marked its libraries). Without it such a file is refused.
    #[arg(long, requires = "blend")]
    pub force: bool,

    /// Add or replace the groups in an existing .blend, in place (materials using them keep
    /// working); the previous file is kept as FILE.blend1.
    #[arg(long, value_name = "EXISTING.blend")]
    pub into: Option<PathBuf>,

    /// Let --into open a file saved by a newer Blender than the one that runs. Without it,
    /// such a file is refused: the older Blender would drop what it does not know (newer
    /// nodes become undefined ones) when it saves.
    #[arg(long, requires = "into")]
    pub allow_downgrade: bool,

    /// Write a Blender extension (4.2+): drag the .zip into Blender, or Edit ▸ Preferences ▸
    /// Get Extensions ▸ Install from Disk. Enabling it registers the library as the asset
    /// library "Gloffuse", so the groups show in the Asset Browser and in the shader
    /// editor's Add ▸ Shader menu. Needs a Blender 4.2 or later to build; it runs in that
    /// version and later.
    #[arg(long, value_name = "OUT.zip", conflicts_with = "into")]
    pub extension: Option<PathBuf>,

    /// Write the same add-on as a classic add-on, for Blender 3.4 to 4.1 (Edit ▸
    /// Preferences ▸ Add-ons ▸ Install, then tick "Material: Gloffuse"): the asset library,
    /// the Gloffuse panel and its operators. Build it with the oldest Blender it is for (it
    /// runs in that version and later; --blender picks one).
    #[arg(long, value_name = "OUT.zip", conflicts_with = "into")]
    pub addon: Option<PathBuf>,

    /// Which groups to build besides the roughness-only pair (repeatable): view adds
    /// `Brightness Correction View (…)` and `Gloffuse View (…)` (gain 1/E(μ, r)), and
    /// multiscatter adds `Gloffuse Multiscatter (…)`; both add the packed E(μ, r) table.
    #[arg(long, value_parser = one_of(MODES, Mode::key), value_delimiter = ',', default_value = Mode::Roughness.key())]
    pub mode: Vec<Mode>,

    /// The engines to build groups for, comma-separated: cycles builds `Gloffuse (…)` and the
    /// rest, eevee builds `Gloffuse EEVEE (…)` and the rest, calibrated on what EEVEE renders
    /// (every distribution as GGX); cycles,eevee puts both sets into one library [default:
    /// cycles, or the engine the --coefficients were fitted for].
    #[arg(long, value_parser = one_of(ENGINES, Engine::key), value_delimiter = ',')]
    pub engine: Vec<Engine>,

    /// What a coloured correction keeps: exact (the surface's albedo is Color) or physical
    /// (multiple bounces tint and darken a coloured rough surface, as in Multiscatter GGX).
    #[arg(long, value_parser = one_of(COLOR_MODELS, ColorModel::key), default_value = GenerateOptions::default().color_model.key())]
    pub color_model: ColorModel,

    #[command(flatten)]
    pub blender: BlenderArgs,

    /// Print a JSON summary instead of text.
    #[arg(long)]
    pub json: bool,
}

impl GenerateArgs {
    pub fn options(&self) -> GenerateOptions {
        GenerateOptions {
            coefficients: self.coefficients.clone(),
            script: self.script.clone(),
            blend: self.blend.clone(),
            into: self.into.clone(),
            allow_downgrade: self.allow_downgrade,
            force: self.force,
            extension: self.extension.clone(),
            addon: self.addon.clone(),
            audit_catalogue: Some(gloffuse::audit::catalogue::EXTENSION),
            modes: self.mode.clone(),
            engines: self.engine.clone(),
            color_model: self.color_model,
            blender: self.blender.options(false),
        }
    }
}
