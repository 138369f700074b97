//! What the audit's twins put in place of a lobe that loses (Blender's own Multiscatter GGX
//! where it keeps the light, else a gloffuse group: `Gloffuse Multiscatter (…)`, `Gloffuse
//! Layered (…)`, `Gloffuse Anisotropic (…)`, `Gloffuse Glass (…)`, `Gloffuse Refraction
//! (…)`), and those groups: computed only when a job asks for them, and the job run again
//! with them.

use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

use serde::Serialize;

use super::job::{FixOutput, JobRun, JobSettings, run_job};
use crate::Error;
use crate::blender::Blender;
use crate::fit::Coefficients;
use crate::generate::names::{anisotropic_group_name, glass_group_name, refraction_group_name};
use crate::generate::tables::{GlassGroup, GlassTable};
use crate::generate::{
    ColorModel, Curves, GenerateParams, Mode, layered_group_name, multiscatter_group_name,
};
use crate::measure::{BlenderVersion, Distribution, Engine, GlassForm};

/// A twin that is the node itself with its distribution set to Multiscatter GGX (the same
/// words as `MULTISCATTER_TWIN` in `audit_rules.py`, which sets it).
pub const BLENDER_MULTISCATTER: &str = "Multiscatter GGX";

/// Twins by Blender distribution enum (`GGX`, …); a distribution missing has none here.
type Names = BTreeMap<&'static str, String>;

/// The twin of each kind of lobe the audit replaces, in one Blender: a gloffuse group's
/// name, or [`BLENDER_MULTISCATTER`] where Blender's own keeps the light. The job picks
/// by the node and asks for the groups it uses (`needs`).
#[derive(Clone, Debug, Serialize)]
pub struct TwinNames {
    /// An isotropic glossy lobe (the Multiscatter group; GGX's twin is Blender's own).
    multiscatter: Names,
    /// A dielectric coat over a diffuse base (a Mix by Fresnel, a 3.x Principled BSDF).
    layered: Names,
    /// An anisotropic glossy lobe: the anisotropic group, in the Blenders that render it.
    /// It keeps the lobe and restores each view's loss, so the highlight keeps its shape;
    /// 3.x's random-walk Multiscatter GGX keeps the light too, but sends what bounces
    /// between microfacets elsewhere (in a lit scene its sphere correlates 0.95 with the
    /// original's, the group's 0.99: `tests/audit_lobe_fixes.rs`).
    anisotropic: Names,
    /// A Glass BSDF: Blender's own Multiscatter GGX glass where it is a random walk
    /// (3.0–3.5), else the glass group (none in 3.5, whose glass no table describes).
    glass: Names,
    /// A Refraction BSDF, which no Blender compensates: the refraction group.
    refraction: Names,
}

impl TwinNames {
    pub fn new(version: BlenderVersion) -> Self {
        let by = |name: &dyn Fn(Distribution) -> Option<String>| -> Names {
            Distribution::ALL
                .into_iter()
                .filter_map(|d| Some((d.blender_enum(), name(d)?)))
                .collect()
        };
        let blender = || Some(BLENDER_MULTISCATTER.to_string());
        let glass_groups = GlassTable::builds_groups_for(version);
        let dielectric = |d| glass_groups && Mode::Glass.has_group_of(d);
        TwinNames {
            multiscatter: by(&|d| Some(multiscatter_group_name(Engine::Cycles, d))),
            layered: by(&|d| Some(layered_group_name(d))),
            anisotropic: by(&|d| {
                Mode::Anisotropic
                    .renders_group_of(d, version)
                    .then(|| anisotropic_group_name(d))
            }),
            glass: by(&|d| match GlassGroup::of(d, GlassForm::of(version)) {
                GlassGroup::Multiscatter => blender(),
                GlassGroup::Gain => dielectric(d).then(|| glass_group_name(d)),
            }),
            refraction: by(&|d| dielectric(d).then(|| refraction_group_name(d))),
        }
    }
}

/// The gloffuse groups twins use, built on a job's first request and grown to cover every
/// later one: their tables take seconds to compute, so an audit whose materials need none
/// never computes them, and one that does computes only the (mode, distribution) pairs
/// asked, each once.
pub(super) struct TwinGroups<'a> {
    blender: &'a Blender,
    needs: BTreeSet<(Mode, Distribution)>,
    /// Each distribution's groups, for the modes asked of it.
    by_distribution: BTreeMap<Distribution, GenerateParams>,
    /// All of them in one document.
    params: Option<GenerateParams>,
}

impl<'a> TwinGroups<'a> {
    pub(super) fn new(blender: &'a Blender) -> Self {
        TwinGroups {
            blender,
            needs: BTreeSet::new(),
            by_distribution: BTreeMap::new(),
            params: None,
        }
    }

    /// Groups covering `needs` (the job's (mode, distribution enum) pairs) and every earlier need.
    fn cover(&mut self, needs: &[(String, String)], log: &Path) -> Result<&GenerateParams, Error> {
        let mut grown = BTreeSet::new();
        for (mode, distribution) in needs {
            let need = Mode::ALL
                .into_iter()
                .find(|m| m.key() == mode)
                .zip(distribution.parse::<Distribution>().ok())
                .filter(|(m, d)| {
                    matches!(m, Mode::Multiscatter | Mode::Layered)
                        || m.renders_group_of(*d, self.blender.version)
                })
                .ok_or_else(|| Error::Blender {
                    message: format!("the audit job asked for groups gloffuse does not build ({mode}, {distribution})").into(),
                    log: Some(log.to_path_buf()),
                    command: None,
                })?;
            if self.needs.insert(need) {
                grown.insert(need.1);
            }
        }
        if !grown.is_empty() {
            let (coefficients, source) =
                Coefficients::load_or_preset(None, Engine::Cycles, self.blender.version)?;
            for d in grown {
                let mut one = coefficients.clone();
                one.distributions.retain(|k, _| *k == d);
                let modes: Vec<Mode> = Mode::ALL
                    .into_iter()
                    .filter(|m| self.needs.contains(&(*m, d)))
                    .collect();
                let params = GenerateParams::new(
                    Curves::Pinned {
                        coefficients: &one,
                        name: &source,
                    },
                    &[self.blender.version.masking()],
                    &modes,
                    ColorModel::Exact,
                )?;
                self.by_distribution.insert(d, params);
            }
            let mut each = self.by_distribution.values();
            let mut all = each.next().expect("a distribution was asked for").clone();
            all.groups
                .extend(each.flat_map(|p| p.groups.iter().cloned()));
            self.params = Some(all);
        }
        self.params.as_ref().ok_or_else(|| Error::Blender {
            message: "the audit job asked for no groups and gave no reason to run again".into(),
            log: Some(log.to_path_buf()),
            command: None,
        })
    }
}

/// Runs the job on `file`, and again with the gloffuse groups its twins asked for.
pub(super) fn run_twinned(
    s: &JobSettings,
    twins: &mut TwinGroups,
    file: &Path,
    fix: Option<FixOutput>,
) -> Result<JobRun, Error> {
    let first = run_job(
        &JobSettings {
            groups: twins.params.as_ref(),
            ..*s
        },
        file,
        fix,
    )?;
    if first.result.needs.is_empty() {
        return Ok(first);
    }
    let groups = twins.cover(&first.result.needs, &first.log)?;
    let second = run_job(
        &JobSettings {
            groups: Some(groups),
            ..*s
        },
        file,
        fix,
    )?;
    if second.result.needs.is_empty() {
        Ok(second)
    } else {
        Err(Error::Blender {
            message: "the audit job asked again for the groups it was given".into(),
            log: Some(second.log),
            command: None,
        })
    }
}
