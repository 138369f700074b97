//! The generate job's parameter document: which node groups to build, with their names,
//! descriptions, curves and packed tables. It travels to Python as JSON (see
//! [`super::script`]).

use serde::Serialize;

use super::catalogs::Catalogs;
use super::names::{
    anisotropic_group_name, correction_group_name, engine_infix, glass_group_name,
    layered_group_name, multiscatter_group_name, normal_group_name, refraction_group_name,
    shader_group_name,
};
use super::tables::{
    AlbedoTable, AnisotropicTable, COAT_TABLE_SIZE, CoatTable, GlassTable, VIEW_TABLE_SIZE,
};
use super::vocabulary::{ColorModel, Mode};
use crate::error::{Error, Field};
use crate::fit::{Coefficients, ColorSpace, Curve, Target, preset_for_masking};
use crate::measure::{BlenderVersion, Distribution, Engine, Masking};

/// The names of the view-dependent groups of one distribution; a name is there when a
/// mode asks for its group.
#[derive(Clone, Debug, Serialize)]
pub struct ViewNames {
    #[serde(skip_serializing_if = "Option::is_none")]
    pub correction_group: Option<String>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub shader_group: Option<String>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub multiscatter_group: Option<String>,
}

/// What one masking family (one Blender version range) builds for a distribution: the
/// curve, its description, and the packed E(μ, r) table of the view modes.
#[derive(Clone, Debug, Serialize)]
pub struct FamilySpec {
    pub masking: Masking,
    /// The preset or file the curve comes from, for the descriptions.
    pub coefficients_source: String,
    pub description: String,
    pub curve: Curve,
    /// Name of the packed float image holding `table` (view modes only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub image: Option<String>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub table: Option<AlbedoTable>,
    /// Name of the packed float image holding `coat_table` (layered mode only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub coat_image: Option<String>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub coat_table: Option<CoatTable>,
    /// Name of the packed float image holding `coat_table.gain` (layered Beckmann only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub coat_gain_image: Option<String>,
    /// Name of the packed float image holding `anisotropic_table` (anisotropic mode, where
    /// this family's Blenders render the lobe).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub anisotropic_image: Option<String>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub anisotropic_table: Option<AnisotropicTable>,
    /// The prefix of the packed float images holding `glass_table`'s four tables (glass
    /// mode): `<prefix> glass entering`, … .
    #[serde(skip_serializing_if = "Option::is_none")]
    pub glass_image: Option<String>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub glass_table: Option<GlassTable>,
}

/// One distribution's node groups, as the Python side builds them. The script picks the
/// family of the Blender it runs in (see [`GenerateParams::height_correlated_from`]).
#[derive(Clone, Debug, Serialize)]
pub struct GroupSpec {
    /// Written as Blender's enum for the Glossy node's distribution (`GGX`, …).
    #[serde(serialize_with = "as_blender_enum")]
    pub distribution: Distribution,
    /// The engine the groups are calibrated for (it is in their names, and it decides
    /// which normal the view-dependent groups read the view cosine at).
    pub engine: Engine,
    pub correction_group: String,
    pub shader_group: String,
    /// The helper group the view-dependent groups take the shading normal and view
    /// cosine from (only when a per-pixel mode asks for them): see [`normal_group_name`].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub normal_group: Option<String>,
    /// The view and multiscatter groups (only when a mode asks for them).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub view: Option<ViewNames>,
    /// `Gloffuse Layered (…)` (layered mode only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub layered_group: Option<String>,
    /// `Gloffuse Anisotropic (GGX | Beckmann)` (anisotropic mode; a script builds it only
    /// in the Blenders whose family carries its table: not Beckmann in 3.0–3.4).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub anisotropic_group: Option<String>,
    /// `Gloffuse Glass (GGX)` and `Gloffuse Refraction (GGX)` (glass mode; a script builds
    /// them only in the Blenders whose family's table is theirs: not in 3.5).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub glass_group: Option<String>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub refraction_group: Option<String>,
    pub families: Vec<FamilySpec>,
}

impl GroupSpec {
    /// The shader group a furnace sphere of this mode is shaded with.
    pub fn shader_for(&self, mode: Mode) -> Option<&str> {
        let view = self.view.as_ref();
        match mode {
            Mode::Roughness => Some(&self.shader_group),
            Mode::View => view.and_then(|v| v.shader_group.as_deref()),
            Mode::Multiscatter => view.and_then(|v| v.multiscatter_group.as_deref()),
            Mode::Layered => self.layered_group.as_deref(),
            Mode::Anisotropic => self.anisotropic_group.as_deref(),
            Mode::Glass => self.glass_group.as_deref(),
        }
    }

    /// Every group name this spec builds, in build order.
    pub fn group_names(&self) -> Vec<String> {
        let mut names = vec![self.correction_group.clone(), self.shader_group.clone()];
        if let Some(v) = &self.view {
            let view = [&v.correction_group, &v.shader_group, &v.multiscatter_group];
            names.extend(view.into_iter().flatten().cloned());
        }
        names.extend(self.layered_group.iter().cloned());
        names.extend(self.anisotropic_group.iter().cloned());
        names.extend(self.glass_group.iter().cloned());
        names.extend(self.refraction_group.iter().cloned());
        names
    }
}

/// Where the curves come from.
#[derive(Clone, Copy, Debug)]
pub enum Curves<'a> {
    /// One coefficients file (or preset) for every family, calibrated for the engine its
    /// entries name; `name` is what it was loaded by.
    Pinned {
        coefficients: &'a Coefficients,
        name: &'a str,
    },
    /// For each engine, each family's own preset (Cycles: `blender-3` for separable,
    /// `blender-4` for height-correlated masking; EEVEE: `eevee`, one family).
    Presets(&'a [Engine]),
}

/// The parameter document of the generate job.
#[derive(Clone, Debug, Serialize)]
pub struct GenerateParams {
    pub gloffuse_version: &'static str,
    /// The first Blender version whose Cycles uses height-correlated masking: the script
    /// builds the separable family in older versions, the height-correlated one from this
    /// version on (or the only family it carries).
    pub height_correlated_from: [u32; 2],
    pub color_model: ColorModel,
    /// The asset catalogs the groups are assigned to.
    pub catalogs: Catalogs,
    /// The assets' author; their licence and copyright (Blender 3.6+ stores those two).
    pub asset_author: &'static str,
    pub asset_license: &'static str,
    pub asset_copyright: &'static str,
    /// Render a preview of every group (the generate job sets it for a .blend).
    pub previews: bool,
    pub groups: Vec<GroupSpec>,
}

/// The licence of the assets gloffuse generates (Blender's extension rules ask for CC0 or
/// a compatible licence for bundled assets).
pub const ASSET_LICENSE: &str = "CC0-1.0";
pub const ASSET_AUTHOR: &str = "gloffuse";
pub const ASSET_COPYRIGHT: &str = "Generated by gloffuse; dedicated to the public domain (CC0 1.0)";

impl GenerateParams {
    /// The groups for every distribution the curves hold, for each masking family in
    /// `families` (EEVEE: its one model), with the view-dependent groups `modes` ask for.
    pub fn new(
        curves: Curves,
        families: &[Masking],
        modes: &[Mode],
        color_model: ColorModel,
    ) -> Result<Self, Error> {
        let engines = match curves {
            Curves::Pinned { coefficients, .. } => vec![coefficients.engine()],
            Curves::Presets(engines) => engines.to_vec(),
        };
        if engines.contains(&Engine::Eevee) {
            check_eevee_modes(modes)?;
        }
        let mut groups = Vec::new();
        for engine in engines {
            let mut loaded = Vec::new();
            for masking in engine_families(engine, families) {
                let (coefficients, name) = match curves {
                    Curves::Pinned { coefficients, name } => {
                        (coefficients.clone(), name.to_string())
                    }
                    Curves::Presets(_) => {
                        let name = preset_for_masking(engine, masking);
                        (Coefficients::load(name)?, name.to_string())
                    }
                };
                loaded.push((masking, coefficients, name));
            }
            let distributions: Vec<Distribution> = loaded
                .first()
                .map(|(_, c, _)| c.distributions.keys().copied().collect())
                .unwrap_or_default();
            groups.extend(
                distributions
                    .into_iter()
                    .map(|d| group_spec(engine, d, &loaded, modes, color_model)),
            );
        }
        let first = BlenderVersion::HEIGHT_CORRELATED_FROM;
        Ok(GenerateParams {
            gloffuse_version: env!("CARGO_PKG_VERSION"),
            height_correlated_from: [first.major, first.minor],
            color_model,
            catalogs: Catalogs::default(),
            asset_author: ASSET_AUTHOR,
            asset_license: ASSET_LICENSE,
            asset_copyright: ASSET_COPYRIGHT,
            previews: false,
            groups,
        })
    }

    /// Every group name the script builds, in build order: each spec's groups, after the
    /// normal helper it is the first to use.
    pub fn group_names(&self) -> Vec<String> {
        let mut names: Vec<String> = Vec::new();
        for spec in &self.groups {
            if let Some(normal) = &spec.normal_group
                && !names.contains(normal)
            {
                names.push(normal.clone());
            }
            names.extend(spec.group_names());
        }
        names
    }
}

/// The masking families an engine's groups carry: each of Cycles' `families` as that
/// engine renders it, once (EEVEE's one model serves every Blender version).
fn engine_families(engine: Engine, families: &[Masking]) -> Vec<Masking> {
    let mut rendered: Vec<Masking> = families.iter().map(|&m| engine.masking(m)).collect();
    rendered.dedup();
    rendered
}

/// Each of `modes` is built for EEVEE, or the first in `Mode::ALL`'s order that is not is
/// refused, naming those that are.
fn check_eevee_modes(modes: &[Mode]) -> Result<(), Error> {
    let Some((mode, why)) = Mode::ALL
        .into_iter()
        .filter(|m| modes.contains(m))
        .find_map(|m| Some((m, m.cycles_only()?)))
    else {
        return Ok(());
    };
    let eevee: Vec<&str> = Mode::ALL
        .into_iter()
        .filter(|m| m.cycles_only().is_none())
        .map(Mode::key)
        .collect();
    let (last, rest) = eevee.split_last().expect("some modes render in EEVEE");
    Err(Error::input(
        Field::Mode,
        mode.key(),
        format!("{} or {last} for EEVEE: {why}", rest.join(", ")),
    ))
}

/// One distribution's groups for one engine: names, and per family the curve and the tables
/// of the BSDF that engine renders.
fn group_spec(
    engine: Engine,
    d: Distribution,
    loaded: &[(Masking, Coefficients, String)],
    modes: &[Mode],
    color_model: ColorModel,
) -> GroupSpec {
    let wants = |m: Mode| modes.contains(&m);
    // Every per-pixel group reads the shading normal; those of `reads_view_table` E(μ, r).
    let normal = modes.iter().any(|m| m.per_pixel());
    let views = modes.iter().any(|m| m.reads_view_table());
    let layered = wants(Mode::Layered);
    let anisotropic = wants(Mode::Anisotropic) && Mode::Anisotropic.has_group_of(d);
    let glass = wants(Mode::Glass) && Mode::Glass.has_group_of(d);
    let infix = engine_infix(engine);
    GroupSpec {
        distribution: d,
        engine,
        correction_group: correction_group_name(engine, d),
        shader_group: shader_group_name(engine, d),
        normal_group: normal.then(|| normal_group_name(engine)),
        layered_group: layered.then(|| layered_group_name(d)),
        anisotropic_group: anisotropic.then(|| anisotropic_group_name(d)),
        glass_group: glass.then(|| glass_group_name(d)),
        refraction_group: glass.then(|| refraction_group_name(d)),
        view: (wants(Mode::View) || wants(Mode::Multiscatter)).then(|| ViewNames {
            correction_group: wants(Mode::View)
                .then(|| format!("Brightness Correction{infix} View ({})", d.label())),
            shader_group: wants(Mode::View)
                .then(|| format!("Gloffuse{infix} View ({})", d.label())),
            multiscatter_group: wants(Mode::Multiscatter)
                .then(|| multiscatter_group_name(engine, d)),
        }),
        families: loaded
            .iter()
            .filter_map(|(masking, c, name)| {
                let e = c.distributions.get(&d)?;
                // EEVEE renders every distribution as its GGX: the tables are that BSDF's.
                let (model, model_masking) = engine.model(d, *masking);
                let rendered_anisotropic = anisotropic && family_renders_anisotropic(*masking, d);
                Some(FamilySpec {
                    masking: *masking,
                    coefficients_source: format!("{name} ({})", c.name),
                    description: describe(engine, d, e, name),
                    curve: e.curve.clone(),
                    image: views.then(|| {
                        format!("Gloffuse E(mu, r) ({}, {})", model.label(), model_masking)
                    }),
                    table: views
                        .then(|| AlbedoTable::compute(model, model_masking, VIEW_TABLE_SIZE)),
                    coat_image: layered
                        .then(|| format!("Gloffuse coat A ({}, {})", d.label(), masking)),
                    coat_table: layered.then(|| CoatTable::compute(d, *masking, COAT_TABLE_SIZE)),
                    coat_gain_image: (layered && d == Distribution::Beckmann)
                        .then(|| format!("Gloffuse coat gain ({}, {})", d.label(), masking)),
                    anisotropic_image: rendered_anisotropic.then(|| {
                        format!("Gloffuse E(mu, phi, ax, ay) ({}, {})", d.label(), masking)
                    }),
                    anisotropic_table: rendered_anisotropic
                        .then(|| AnisotropicTable::compute(d, *masking)),
                    glass_image: glass
                        .then(|| format!("Gloffuse E(mu, r, eta) ({}, {})", d.label(), masking)),
                    glass_table: glass.then(|| GlassTable::compute(d, *masking, color_model)),
                })
            })
            .collect(),
    }
}

/// Whether the Blenders of a masking family render the anisotropic lobe of `d` (not
/// Beckmann in 3.0–3.4, the separable family): where they do not, the family carries no
/// table and the script builds no anisotropic group for `d`.
fn family_renders_anisotropic(masking: Masking, d: Distribution) -> bool {
    let first = match masking {
        Masking::Separable => BlenderVersion::OLDEST,
        Masking::HeightCorrelated => BlenderVersion::HEIGHT_CORRELATED_FROM,
    };
    first.renders_anisotropic(d)
}

/// The description of a distribution's groups: what the curve restores, where it comes
/// from, and what the other engine makes of it.
fn describe(
    engine: Engine,
    d: Distribution,
    e: &crate::fit::coefficients::Entry,
    source: &str,
) -> String {
    let what = match engine {
        Engine::Cycles => format!("a white {} Glossy BSDF", d.label()),
        Engine::Eevee => format!(
            "a white {} Glossy BSDF in EEVEE (which renders it as GGX)",
            d.label()
        ),
    };
    format!(
        "Restores {what} to 100 % brightness under even light: gain = 100 / f(r), fitted to the sphere's {} brightness ({} masking{}). Coefficients: {}. {}",
        match e.target {
            Target::Mean => "mean",
            Target::Center => "centre",
        },
        e.masking,
        match e.color_space {
            ColorSpace::Linear => "",
            ColorSpace::Display => "; display-referred percentages, not a true linear gain",
        },
        source,
        in_the_other_engine(engine, d, e.masking),
    )
}

/// The roughness values of the EEVEE measurements quoted in the Cycles groups' descriptions.
const EEVEE_ROUGHNESS: [f64; 4] = [0.25, 0.5, 0.75, 1.0];

/// The Blender each Cycles family's EEVEE figures were measured in (separable, then
/// height-correlated).
const EEVEE_MEASURED_IN: [&str; 2] = ["3.4.1 (EEVEE Legacy)", "4.5.15 (EEVEE Next)"];

/// A white sphere with the Cycles group of `d` and `masking`'s preset, rendered in EEVEE
/// (`verify --engine eevee --coefficients blender-3|blender-4 -r 0.25,0.5,0.75,1`, 1 spp,
/// 64 px), in percent at [`EEVEE_ROUGHNESS`]; `tests/eevee_e2e.rs` re-renders them.
pub fn in_eevee(d: Distribution, masking: Masking) -> [f64; 4] {
    match (masking, d) {
        (Masking::Separable, Distribution::Beckmann) => [98.8, 90.6, 74.1, 57.4],
        (Masking::Separable, Distribution::Ggx) => [99.9, 100.0, 100.0, 100.0],
        (Masking::Separable, Distribution::AshikhminShirley) => [104.4, 112.1, 118.8, 156.9],
        (Masking::HeightCorrelated, Distribution::Beckmann) => [98.0, 89.6, 73.2, 56.3],
        (Masking::HeightCorrelated, Distribution::Ggx) => [99.0, 98.6, 96.9, 91.4],
        (Masking::HeightCorrelated, Distribution::AshikhminShirley) => [103.4, 110.8, 117.6, 155.7],
    }
}

/// What a group does in the engine it is not calibrated for, as measured (docs/RESULTS.md, "EEVEE").
fn in_the_other_engine(engine: Engine, d: Distribution, masking: Masking) -> String {
    match engine {
        Engine::Eevee => "In Cycles use the groups without EEVEE in their names.".into(),
        Engine::Cycles => {
            let measured = in_eevee(d, masking)
                .iter()
                .map(|p| format!("{p} %"))
                .collect::<Vec<_>>()
                .join(", ");
            format!(
                "In EEVEE a white sphere with this group renders at {measured} of the light at roughness {} (measured in Blender {}); use the EEVEE groups there.",
                EEVEE_ROUGHNESS.map(|r| r.to_string()).join(", "),
                EEVEE_MEASURED_IN[usize::from(masking == Masking::HeightCorrelated)]
            )
        }
    }
}
fn as_blender_enum<S: serde::Serializer>(d: &Distribution, s: S) -> Result<S::Ok, S::Error> {
    s.serialize_str(d.blender_enum())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// EEVEE takes the modes whose groups are built for it; of the others the first in
    /// `Mode::ALL`'s order is refused, naming the modes EEVEE takes and why.
    #[test]
    fn eevee_refuses_the_cycles_only_modes() {
        assert!(check_eevee_modes(&[Mode::Roughness, Mode::View, Mode::Multiscatter]).is_ok());
        let refused = check_eevee_modes(&[Mode::Glass, Mode::Layered]).unwrap_err();
        let text = refused.to_string();
        assert!(text.contains("layered"), "{text}");
        assert!(
            text.contains(
                "roughness, view or multiscatter for EEVEE: the layered groups are calibrated \
                 for Cycles, and in EEVEE's furnace their rings miss 2 % (docs/EEVEE.md)"
            ),
            "{text}"
        );
    }
}
