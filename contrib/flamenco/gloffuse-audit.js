// SPDX-License-Identifier: GPL-3.0-or-later
//
// Flamenco (3.3+) job type: a sharded `gloffuse audit` of .blend files.
// Put this file in the `scripts` folder next to `flamenco-manager`.
//
// The job is N shard tasks (type `blender`: they run Blender, so only workers
// that take `blender` tasks get them) and one merge task (type `misc`: it only
// joins JSON/JUnit/pictures) that depends on every shard task.

// gloffuse option that makes a check failure exit 0 instead of 1 (exit 2, "could
// not run", is unchanged). Flamenco's `exec` command fails a task on any non-zero
// exit, and a task only becomes runnable once all its dependencies are
// `completed`, so without it a shard with failing materials would block the
// merge (and be re-run on other workers as if the worker were at fault).
// Both `gloffuse audit` and `gloffuse report merge` take it.
const EXIT_ZERO_FLAG = "--exit-zero";

// Separator between the paths of the `paths` setting. Job settings cannot be
// arrays (AvailableJobSettingType: string, int32, float, bool), and `;` occurs
// neither in Windows drive letters (`:`) nor in ordinary file names.
const PATH_SEPARATOR = ";";

const JOB_TYPE = {
    label: "gloffuse audit (sharded)",
    description: "Audit the materials of .blend files with gloffuse, split over several workers, then merge the reports",
    settings: [
        { key: "paths", type: "string", required: true,
          description: "The .blend files or folders to audit, separated by ';'. Absolute paths as the workers see them (a Flamenco variable such as {shared}/assets works)" },
        { key: "shards", type: "int32", required: true, default: 4, propargs: { min: 1, max: 1000 },
          description: "Number of shard tasks; each audits its own part of the files" },
        { key: "output_dir", type: "string", subtype: "dir_path", required: true,
          description: "Shared folder for the shard reports (shard-K/, shard-K.xml) and the merged ones (merged/, merged.json, merged.xml). '{timestamp}' is replaced by the job's creation time" },
        { key: "gloffuse_exe", type: "string", required: false, default: "gloffuse",
          description: "The gloffuse executable on the workers: a path, a name found on the worker's PATH, or a Flamenco variable such as {gloffuse}" },
        { key: "extra_args", type: "string", required: false, default: "",
          description: "Extra options for every 'gloffuse audit' shard, split like a shell command line, e.g. --fail-on creates,error --spp 256 (Flamenco 3.6+)" },
    ],
};

// Options the job sets itself; passing them again in extra_args would make the
// shards disagree with the merge (or with each other).
const RESERVED_OPTIONS = ["--shard", "--report", "--junit", "--blender", EXIT_ZERO_FLAG];

const MAX_SHARDS = 1000;

function compileJob(job) {
    // Validate everything before authoring any task: a thrown error rejects the
    // submission (the Manager answers 400 with the message) with no job made.
    const settings = job.settings || {};
    const paths = parsePaths(settings.paths);
    const shards = parseShards(settings.shards);
    const outputDir = parseOutputDir(settings.output_dir, job.created);
    const gloffuse = parseExe(settings.gloffuse_exe);
    const extraArgs = parseExtraArgs(settings.extra_args);

    // Show the folder actually used (after {timestamp}) in the web interface,
    // as the built-in Simple Blender Render job does for its output path.
    settings.output_dir = outputDir;

    const shardTasks = [];
    const shardDirs = [];
    for (let k = 1; k <= shards; k++) {
        const reportDir = joinPath(outputDir, `shard-${k}`);
        shardDirs.push(reportDir);

        const task = author.Task(`audit-shard-${k}-of-${shards}`, "blender");
        // `exec` runs `exe` directly with `args` as an array (no shell), so
        // paths with spaces stay single arguments. `{blender}` is expanded per
        // worker by the Manager, as it is for every string in a command.
        task.addCommand(author.Command("exec", {
            exe: gloffuse,
            args: ["audit"].concat(extraArgs, [
                "--shard", `${k}/${shards}`,
                "--report", reportDir,
                "--junit", joinPath(outputDir, `shard-${k}.xml`),
                "--blender", "{blender}",
                EXIT_ZERO_FLAG,
                // `--` ends the options: a path starting with '-' is still a path.
                "--",
            ], paths),
        }));
        shardTasks.push(task);
    }

    const mergeTask = author.Task("merge-reports", "misc");
    mergeTask.addCommand(author.Command("exec", {
        exe: gloffuse,
        args: ["report", "merge"].concat(shardDirs, [
            "--json", joinPath(outputDir, "merged.json"),
            "--junit", joinPath(outputDir, "merged.xml"),
            "--report", joinPath(outputDir, "merged"),
            // The merged verdict is in merged.json / merged.xml; exit 1 would
            // make Flamenco retry the merge on other workers and fail the task.
            EXIT_ZERO_FLAG,
        ]),
    }));
    // Flamenco only schedules a task once all of its dependencies are completed.
    for (const task of shardTasks) {
        mergeTask.addDependency(task);
    }

    for (const task of shardTasks) {
        job.addTask(task);
    }
    job.addTask(mergeTask);
    print(`gloffuse audit: ${shards} shard(s) of ${paths.length} path(s) into ${outputDir}`);
}

function settingError(key, message) {
    return new Error(`gloffuse-audit: setting '${key}': ${message}`);
}

// An absolute path on any worker platform, or one starting with a Flamenco
// variable ({shared}/...), which the Manager expands per worker. A relative
// path would resolve against each worker's own working directory.
function isAbsoluteOrVariable(p) {
    return /^(\/|\\\\|[A-Za-z]:[\\/]|\{[^}]+\})/.test(p);
}

function parsePaths(value) {
    if (typeof value !== "string" || value.trim() === "") {
        throw settingError("paths", "required: one or more .blend files or folders, separated by ';'");
    }
    const paths = value.split(PATH_SEPARATOR)
        .map((p) => p.trim())
        .filter((p) => p !== "");
    if (paths.length === 0) {
        throw settingError("paths", `no path in '${value}': give one or more .blend files or folders, separated by ';'`);
    }
    for (const p of paths) {
        if (!isAbsoluteOrVariable(p)) {
            throw settingError("paths", `'${p}' is relative: give an absolute path that every worker sees (or start it with a Flamenco variable such as {shared})`);
        }
    }
    return paths;
}

function parseShards(value) {
    if (value === undefined || value === null || value === "") {
        throw settingError("shards", "required: the number of shard tasks, 1 or more");
    }
    const n = typeof value === "string" ? Number(value.trim()) : value;
    if (typeof n !== "number" || !Number.isInteger(n) || n < 1 || n > MAX_SHARDS) {
        throw settingError("shards", `'${value}' is not a whole number from 1 to ${MAX_SHARDS}`);
    }
    return n;
}

function parseOutputDir(value, created) {
    if (typeof value !== "string" || value.trim() === "") {
        throw settingError("output_dir", "required: a shared folder for the reports, seen by every worker");
    }
    let dir = value.trim();
    if (dir.indexOf("{timestamp}") >= 0) {
        dir = dir.split("{timestamp}").join(formatTimestampLocal(created));
    }
    if (!isAbsoluteOrVariable(dir)) {
        throw settingError("output_dir", `'${dir}' is relative: the merge task must see every shard's report, so give an absolute path on shared storage (or start it with a Flamenco variable such as {shared})`);
    }
    return dir;
}

function parseExe(value) {
    if (value === undefined || value === null || value === "") {
        return "gloffuse";
    }
    if (typeof value !== "string" || value.trim() === "") {
        throw settingError("gloffuse_exe", "must be a path or command name, e.g. gloffuse");
    }
    return value.trim();
}

function parseExtraArgs(value) {
    if (value === undefined || value === null || String(value).trim() === "") {
        return [];
    }
    if (typeof shellSplit !== "function") {
        throw settingError("extra_args", "needs Flamenco 3.6 or newer (shellSplit); leave it empty on older Managers");
    }
    let args;
    try {
        args = shellSplit(String(value));
    } catch (e) {
        throw settingError("extra_args", `cannot split '${value}' like a command line: ${errorText(e)}`);
    }
    for (const arg of args) {
        const option = arg.split("=")[0];
        if (arg === "--") {
            throw settingError("extra_args", "must not contain '--': the job puts the paths after it");
        }
        if (RESERVED_OPTIONS.indexOf(option) >= 0) {
            throw settingError("extra_args", `must not contain ${option}: the job sets it for every shard`);
        }
    }
    return args;
}

// Flamenco's shellSplit throws the Go error itself, whose text is behind error().
function errorText(e) {
    if (e && typeof e.error === "function") return e.error();
    if (e && e.message) return e.message;
    return String(e);
}

// Join with the separator the folder already uses, without normalising it
// (Flamenco's path.join cleans the path, which would turn //server/share into
// /server/share). Windows and gloffuse accept either separator anyway.
function joinPath(dir, name) {
    const sep = dir.indexOf("\\") >= 0 && dir.indexOf("/") < 0 ? "\\" : "/";
    return dir.replace(/[\\/]+$/, "") + sep + name;
}
