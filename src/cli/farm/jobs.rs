//! A sharded audit as the job of a farm studios already run: a Slurm array job with a
//! dependent merge job, or an Open Job Description template (what AWS Deadline Cloud
//! submits). Both run the same command lines — `gloffuse audit … --shard K/N` per shard, then
//! `gloffuse report merge` — into one folder layout:
//!
//! ```text
//! DIR/shard-K/       shard K's report (report.json, report.html, materials/)
//! DIR/shard-K.xml    its JUnit
//! DIR/merged/        the merged report, as one unsharded audit writes it
//! DIR/merged.json    DIR/merged.xml    DIR/merged.sarif
//! DIR/logs/          the Slurm jobs' output
//! ```

use std::path::PathBuf;

use serde_json::{Value, json};

use gloffuse::blender::process::shell_quote;
use gloffuse::{Error, Field};

/// What a farm runs: the audit of `paths` in `shards` parts, by `program` on every node.
#[derive(Clone, Debug, PartialEq)]
pub struct FarmJob {
    /// gloffuse on the nodes.
    pub program: String,
    /// The .blend files and folders to audit, as the nodes see them.
    pub paths: Vec<PathBuf>,
    /// More `audit` flags (`--spp 64`, `--blender …`), passed as they are.
    pub audit_flags: Vec<String>,
    pub shards: usize,
    /// Where every shard's report and the merged one go: a folder all nodes share.
    pub dir: PathBuf,
    /// The folder relative paths are taken from.
    pub workdir: PathBuf,
}

/// The merged report's folder inside the job's folder.
pub const MERGED: &str = "merged";

impl FarmJob {
    /// `audit` for shard `k` (a number, or the farm's placeholder for it), with the paths
    /// and the job's folder spelled as given (literal, or the farm's placeholders).
    fn shard_args(&self, paths: &[String], dir: &str, k: &str) -> Vec<String> {
        let mut args = vec!["audit".to_string()];
        args.extend(self.audit_flags.iter().cloned());
        args.extend([
            format!("--shard={k}/{}", self.shards),
            format!("--report={dir}/shard-{k}"),
            format!("--junit={dir}/shard-{k}.xml"),
            "--".to_string(),
        ]);
        args.extend(paths.iter().cloned());
        args
    }

    /// `report merge` of every shard into `dir/merged`.
    fn merge_args(&self, dir: &str) -> Vec<String> {
        let mut args = vec!["report".to_string(), "merge".to_string()];
        args.extend((1..=self.shards).map(|k| format!("{dir}/shard-{k}")));
        args.extend([
            format!("--json={dir}/{MERGED}.json"),
            format!("--junit={dir}/{MERGED}.xml"),
            format!("--sarif={dir}/{MERGED}.sarif"),
            format!("--report={dir}/{MERGED}"),
        ]);
        args
    }

    fn literal_paths(&self) -> Vec<String> {
        self.paths.iter().map(|p| p.display().to_string()).collect()
    }

    fn dir_text(&self) -> String {
        self.dir.display().to_string()
    }
}

/// A Slurm submission: two job scripts and the `sbatch` arguments that submit them.
#[derive(Clone, Debug, PartialEq)]
pub struct SlurmJob {
    /// `audit.sh`: one array task per shard (`$SLURM_ARRAY_TASK_ID` is K).
    pub audit_script: String,
    /// `merge.sh`: the merge, whose exit code is the verdict's.
    pub merge_script: String,
    /// `sbatch` arguments of the array job, the script's path last.
    pub audit_sbatch: Vec<String>,
    /// `sbatch` arguments of the merge job but its dependency (`--dependency=afterany:ID`,
    /// which runs it whatever the shards' exit codes), the script's path last.
    pub merge_sbatch: Vec<String>,
    /// `submit.sh`: both submissions, for a person to run.
    pub submit_script: String,
}

/// Slurm's job scripts for `job`; `sbatch_args` go to both submissions (`--partition=…`).
pub fn slurm(job: &FarmJob, sbatch_args: &[String]) -> SlurmJob {
    let dir = job.dir_text();
    // The shard number comes from Slurm at run time: each argument is quoted around the
    // placeholder, which becomes "$k".
    const K: &str = "\u{0}K\u{0}";
    let command = |args: Vec<String>| {
        std::iter::once(job.program.clone())
            .chain(args)
            .map(|a| match a.contains(K) {
                // An empty piece beside "$k" needs no quotes; an empty argument does ('').
                true => a
                    .split(K)
                    .map(|p| {
                        if p.is_empty() {
                            String::new()
                        } else {
                            shell_quote(p.as_ref())
                        }
                    })
                    .collect::<Vec<_>>()
                    .join("\"$k\""),
                false => shell_quote(a.as_ref()),
            })
            .collect::<Vec<_>>()
            .join(" \\\n    ")
    };
    let audit = command(job.shard_args(&job.literal_paths(), &dir, K));
    let audit_script = format!(
        "#!/bin/bash\n# One shard of a gloffuse audit: Slurm's array task K runs shard K of {n}.\n\
         # Written by `gloffuse farm slurm`; submitted by submit.sh.\nset -u\n\
         k=\"$SLURM_ARRAY_TASK_ID\"\nexec {audit}\n",
        n = job.shards
    );
    let merge_script = format!(
        "#!/bin/bash\n# The merge of every shard's report: exit 0 passed, 1 some materials failed, \
         2 shards missing.\n# Written by `gloffuse farm slurm`; submitted by submit.sh.\nexec {}\n",
        command(job.merge_args(&dir))
    );
    let common = |name: &str, log: &str| {
        let mut args = vec![
            "--parsable".to_string(),
            format!("--job-name={name}"),
            format!("--chdir={}", job.workdir.display()),
            format!("--output={}/logs/{log}", sbatch_pattern(&dir)),
        ];
        args.extend(sbatch_args.iter().cloned());
        args
    };
    let mut audit_sbatch = common("gloffuse-audit", "shard-%a.log");
    audit_sbatch.insert(1, format!("--array=1-{}", job.shards));
    audit_sbatch.push(format!("{dir}/audit.sh"));
    let mut merge_sbatch = common("gloffuse-merge", "merge.log");
    merge_sbatch.push(format!("{dir}/merge.sh"));
    let quoted = |args: &[String]| {
        args.iter()
            .map(|a| shell_quote(a.as_ref()))
            .collect::<Vec<_>>()
            .join(" ")
    };
    let submit_script = format!(
        "#!/bin/bash\n# Submits the sharded audit and its merge (`gloffuse farm slurm`).\nset -euo pipefail\n\
         audit=$(sbatch {})\n\
         merge=$(sbatch --dependency=afterany:\"${{audit%%;*}}\" {})\n\
         echo \"audit: array job $audit ({n} shards); merge: job $merge; merged report: \"{merged}\n",
        quoted(&audit_sbatch),
        quoted(&merge_sbatch),
        n = job.shards,
        merged = shell_quote(format!("{dir}/{MERGED}").as_ref()),
    );
    SlurmJob {
        audit_script,
        merge_script,
        audit_sbatch,
        merge_sbatch,
        submit_script,
    }
}

/// `text` as it must be written in an `sbatch` filename pattern (`--output`) to mean
/// itself: Slurm reads `%` as the start of a replacement (`%a`, the task) and `%%` as `%`.
/// (A pattern holding a backslash is read another way; `farm slurm` refuses such a folder.)
fn sbatch_pattern(text: &str) -> String {
    text.replace('%', "%%")
}

/// An Open Job Description job: its template and the values of its parameters.
#[derive(Clone, Debug, PartialEq)]
pub struct OpenJdJob {
    /// The template (specification `jobtemplate-2023-09`).
    pub template: Value,
    /// `job`'s values of the template's parameters, as `openjd run -p file://…` reads them
    /// (an absolute path cannot be a PATH parameter's default).
    pub parameters: Value,
}

/// An Open Job Description template: step `Audit` with one task per shard, and step `Merge`
/// after it. The paths, the job's folder and the program are job parameters, so a farm can
/// map them. A shard whose materials fail the check exits 0 (`--exit-zero`), since OpenJD
/// runs a dependent step only after every task of the one before succeeded; the merge's exit
/// code carries the verdict.
pub fn openjd(job: &FarmJob) -> Result<OpenJdJob, Error> {
    // Every argument of a template is a format string, with no escape for `{{`.
    if let Some(bad) = job
        .audit_flags
        .iter()
        .chain(&job.literal_paths())
        .find(|a| a.contains("{{") || a.contains("}}"))
    {
        return Err(Error::input(
            Field::Arguments,
            bad,
            "no `{{` or `}}` in an argument of an Open Job Description template (it has no escape for them)",
        ));
    }
    let paths: Vec<String> = (1..=job.paths.len())
        .map(|i| format!("{{{{Param.AuditPath{i}}}}}"))
        .collect();
    let dir = "{{Param.OutputDir}}";
    let mut parameters = vec![
        json!({"name": "Gloffuse", "type": "STRING", "default": job.program,
               "description": "gloffuse on the workers"}),
        json!({"name": "OutputDir", "type": "PATH", "objectType": "DIRECTORY", "dataFlow": "OUT",
               "description": "Every shard's report and the merged one (shared by the workers)"}),
    ];
    let mut values = serde_json::Map::new();
    values.insert("OutputDir".into(), job.dir_text().into());
    for (i, path) in job.literal_paths().into_iter().enumerate() {
        let name = format!("AuditPath{}", i + 1);
        parameters.push(json!({"name": name, "type": "PATH", "dataFlow": "IN",
                               "description": "A .blend file or folder to audit"}));
        values.insert(name, path.into());
    }
    let mut shard = job.shard_args(&paths, dir, "{{Task.Param.Shard}}");
    shard.insert(1, "--exit-zero".to_string());
    let action =
        |args: Vec<String>| json!({"onRun": {"command": "{{Param.Gloffuse}}", "args": args}});
    let template = json!({
        "specificationVersion": "jobtemplate-2023-09",
        "name": format!("gloffuse audit ({} shards)", job.shards),
        "parameterDefinitions": parameters,
        "steps": [
            {
                "name": "Audit",
                "parameterSpace": {"taskParameterDefinitions": [
                    {"name": "Shard", "type": "INT", "range": format!("1-{}", job.shards)}
                ]},
                "script": {"actions": action(shard)}
            },
            {
                "name": "Merge",
                "dependencies": [{"dependsOn": "Audit"}],
                "script": {"actions": action(job.merge_args(dir))}
            }
        ]
    });
    Ok(OpenJdJob {
        template,
        parameters: Value::Object(values),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn job() -> FarmJob {
        FarmJob {
            program: "/opt/gloffuse".into(),
            paths: vec!["/lib/a b.blend".into(), "/lib/more".into()],
            audit_flags: vec!["--spp".into(), "8".into()],
            shards: 3,
            dir: "/farm/run".into(),
            workdir: "/home/me".into(),
        }
    }

    #[test]
    fn slurm_scripts_run_one_shard_per_task_and_merge_all() {
        let s = slurm(&job(), &["--partition=cpu".into()]);
        assert!(s.audit_script.contains("k=\"$SLURM_ARRAY_TASK_ID\""));
        assert!(s.audit_script.contains("--shard=\"$k\"/3 \\\n"));
        assert!(s.audit_script.contains("'/lib/a b.blend'"));
        for k in 1..=3 {
            assert!(s.merge_script.contains(&format!("/farm/run/shard-{k} ")));
        }
        assert_eq!(s.audit_sbatch[1], "--array=1-3");
        assert_eq!(s.audit_sbatch.last().unwrap(), "/farm/run/audit.sh");
        assert!(s.merge_sbatch.contains(&"--partition=cpu".to_string()));
        assert!(
            s.submit_script
                .contains("--dependency=afterany:\"${audit%%;*}\"")
        );
    }

    #[test]
    fn a_bash_runs_the_shard_command_with_k_in_place() {
        // The audit script's command line, with exec swapped for printf: what bash passes.
        let s = slurm(&job(), &[]);
        let line = s.audit_script.split("exec ").nth(1).unwrap();
        let out = std::process::Command::new("bash")
            .arg("-c")
            .arg(format!("k=2; printf '%s\\n' {line}"))
            .output()
            .unwrap();
        let args: Vec<String> = String::from_utf8(out.stdout)
            .unwrap()
            .lines()
            .map(String::from)
            .collect();
        assert_eq!(
            args,
            [
                "/opt/gloffuse",
                "audit",
                "--spp",
                "8",
                "--shard=2/3",
                "--report=/farm/run/shard-2",
                "--junit=/farm/run/shard-2.xml",
                "--",
                "/lib/a b.blend",
                "/lib/more"
            ]
        );
    }

    #[test]
    fn the_template_refuses_format_braces() {
        let mut j = job();
        j.audit_flags = vec!["--blender=/x/{{y}}".into()];
        assert!(openjd(&j).is_err());
        let j = openjd(&job()).unwrap();
        let t = &j.template;
        assert_eq!(
            t["steps"][0]["parameterSpace"]["taskParameterDefinitions"][0]["range"],
            "1-3"
        );
        assert_eq!(t["parameterDefinitions"][2]["name"], "AuditPath1");
        assert_eq!(j.parameters["AuditPath1"], "/lib/a b.blend");
    }
}
