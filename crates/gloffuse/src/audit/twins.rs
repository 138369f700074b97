//! The gloffuse groups the audit's twins use (`Gloffuse Multiscatter (…)`, `Gloffuse Layered
//! (…)`): computed only when a job asks for them, and the job run again with them.

use std::collections::BTreeSet;
use std::path::Path;

use super::job::{FixOutput, JobRun, JobSettings, run_job};
use crate::Error;
use crate::blender::Blender;
use crate::fit::Coefficients;
use crate::generate::{ColorModel, Curves, GenerateParams, Mode};
use crate::measure::{Distribution, Engine};

/// The gloffuse groups twins use, built on a job's first request and grown to cover every
/// later one: their tables take seconds to compute, so an audit whose materials need none
/// never computes them, and one that does computes only the distributions and modes asked.
pub(super) struct TwinGroups<'a> {
    blender: &'a Blender,
    needs: BTreeSet<(Mode, Distribution)>,
    params: Option<GenerateParams>,
}

impl<'a> TwinGroups<'a> {
    pub(super) fn new(blender: &'a Blender) -> Self {
        TwinGroups {
            blender,
            needs: BTreeSet::new(),
            params: None,
        }
    }

    /// Groups covering `needs` (the job's (mode, distribution enum) pairs) and every earlier need.
    fn cover(&mut self, needs: &[(String, String)], log: &Path) -> Result<&GenerateParams, Error> {
        let mut grew = self.params.is_none();
        for (mode, distribution) in needs {
            let need = Mode::ALL
                .into_iter()
                .find(|m| m.key() == mode)
                .zip(distribution.parse::<Distribution>().ok())
                .filter(|(m, _)| matches!(m, Mode::Multiscatter | Mode::Layered))
                .ok_or_else(|| Error::Blender {
                    message: format!("the audit job asked for groups gloffuse does not build ({mode}, {distribution})").into(),
                    log: Some(log.to_path_buf()),
                    command: None,
                })?;
            grew |= self.needs.insert(need);
        }
        if grew {
            let (mut coefficients, source) =
                Coefficients::load_or_preset(None, Engine::Cycles, self.blender.version)?;
            coefficients
                .distributions
                .retain(|d, _| self.needs.iter().any(|(_, n)| n == d));
            let modes: Vec<Mode> = Mode::ALL
                .into_iter()
                .filter(|m| self.needs.iter().any(|(n, _)| n == m))
                .collect();
            self.params = Some(GenerateParams::new(
                Curves::Pinned {
                    coefficients: &coefficients,
                    name: &source,
                },
                &[self.blender.version.masking()],
                &modes,
                ColorModel::Exact,
            )?);
        }
        Ok(self.params.as_ref().expect("built above"))
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
