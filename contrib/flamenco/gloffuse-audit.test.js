// Tests for the Flamenco job type gloffuse-audit.js: `node --test contrib/flamenco/`.
//
// Flamenco runs job scripts in its own JavaScript VM (goja) as plain scripts
// with globals, not as modules. Here the script is evaluated with node:vm in a
// context that provides stand-ins for those globals: a recording `author`
// (Task/Command/addCommand/addDependency, like the Manager's author.go), `print`,
// `alert`, `formatTimestampLocal` and `shellSplit`. This checks the task graph
// compileJob builds, not how a real Manager or Worker runs it.

"use strict";

const { test } = require("node:test");
const assert = require("node:assert/strict");
const fs = require("node:fs");
const path = require("node:path");
const vm = require("node:vm");

const SCRIPT = path.join(__dirname, "gloffuse-audit.js");
const CREATED = new Date(Date.UTC(2024, 4, 6, 7, 8, 9));
const TIMESTAMP = "2024-05-06_070809";

// A small stand-in for Flamenco's shellSplit (github.com/google/shlex): blanks
// separate words, '...' is literal, "..." and a backslash escape.
function shellSplit(s) {
    const words = [];
    let word = null;
    let quote = null;
    for (let i = 0; i < s.length; i++) {
        const c = s[i];
        if (quote === "'") {
            if (c === "'") quote = null; else word += c;
        } else if (quote === '"') {
            if (c === '"') quote = null;
            else if (c === "\\" && i + 1 < s.length) word += s[++i];
            else word += c;
        } else if (/\s/.test(c)) {
            if (word !== null) words.push(word);
            word = null;
        } else {
            if (word === null) word = "";
            if (c === "'" || c === '"') quote = c;
            else if (c === "\\" && i + 1 < s.length) word += s[++i];
            else word += c;
        }
    }
    if (quote) throw new Error("EOF found when expecting closing quote");
    if (word !== null) words.push(word);
    return words;
}

// Loads the script into a fresh context; returns its JOB_TYPE and compileJob.
function load({ withShellSplit = true } = {}) {
    const printed = [];
    const author = {
        // Like author.go: name and type are trimmed and required.
        Task(name, type) {
            name = String(name).trim();
            type = String(type).trim();
            if (!name) throw new Error("author.Task(name, type): name is required");
            if (!type) throw new Error("author.Task(name, type): type is required");
            return {
                name, type, priority: 50, commands: [], dependencies: [],
                addCommand(cmd) { this.commands.push(cmd); },
                addDependency(dep) { this.dependencies.push(dep); },
            };
        },
        Command(name, parameters, totalStepCount) {
            return { name, parameters, totalStepCount: totalStepCount || 0 };
        },
    };
    const globals = {
        author,
        print: (...args) => printed.push(args.join(" ")),
        alert: (...args) => printed.push(args.join(" ")),
        // Flamenco formats in local time; UTC here keeps the test independent of TZ.
        formatTimestampLocal: (d) => d.toISOString().replace(/T(\d\d):(\d\d):(\d\d).*/, "_$1$2$3"),
    };
    if (withShellSplit) globals.shellSplit = shellSplit;
    const context = vm.createContext(globals);
    vm.runInContext(fs.readFileSync(SCRIPT, "utf8"), context, { filename: SCRIPT });
    // Top-level `const` is in the script scope, not on the global object: ask the context.
    return {
        JOB_TYPE: vm.runInContext("JOB_TYPE", context),
        compileJob: vm.runInContext("compileJob", context),
        printed,
    };
}

function fakeJob(settings) {
    return {
        name: "audit the asset library",
        created: CREATED,
        settings: Object.assign({}, settings),
        tasks: [],
        addTask(task) { this.tasks.push(task); },
    };
}

const BASE = {
    paths: "/mnt/farm/assets",
    shards: 3,
    output_dir: "/mnt/farm/audits/run",
    gloffuse_exe: "/opt/gloffuse/gloffuse",
    extra_args: "",
};

function compile(settings, opts) {
    const { compileJob } = load(opts);
    const job = fakeJob(Object.assign({}, BASE, settings));
    compileJob(job);
    return job;
}

// Values made in the vm context have that context's prototypes, which
// deepStrictEqual would count as a difference: compare plain copies.
const plain = (v) => JSON.parse(JSON.stringify(v));

function shardArgs(k, n, { out = "/mnt/farm/audits/run", extra = [], paths = ["/mnt/farm/assets"] } = {}) {
    return ["audit", ...extra,
        "--shard", `${k}/${n}`,
        "--report", `${out}/shard-${k}`,
        "--junit", `${out}/shard-${k}.xml`,
        "--blender", "{blender}",
        "--exit-zero",
        "--", ...paths];
}

function mergeArgs(n, out = "/mnt/farm/audits/run") {
    const dirs = [];
    for (let k = 1; k <= n; k++) dirs.push(`${out}/shard-${k}`);
    return ["report", "merge", ...dirs,
        "--json", `${out}/merged.json`,
        "--junit", `${out}/merged.xml`,
        "--report", `${out}/merged`,
        "--exit-zero"];
}

test("JOB_TYPE: label and settings are well-formed for Flamenco's AvailableJobType", () => {
    const { JOB_TYPE } = load();
    assert.equal(typeof JOB_TYPE.label, "string");
    assert.ok(JOB_TYPE.label.length > 0);
    assert.equal(typeof JOB_TYPE.description, "string");
    assert.ok(Array.isArray(JOB_TYPE.settings));

    // Fields and enums of AvailableJobSetting in Flamenco's flamenco-openapi.yaml.
    const fields = new Set(["key", "type", "subtype", "choices", "propargs", "description",
        "label", "default", "eval", "evalInfo", "visible", "required", "editable"]);
    const types = new Set(["string", "int32", "float", "bool"]);
    const subtypes = new Set(["file_path", "dir_path", "file_name", "hashed_file_path"]);
    const visibilities = new Set(["visible", "hidden", "submission", "web"]);
    const seen = new Set();
    for (const s of JOB_TYPE.settings) {
        for (const f of Object.keys(s)) assert.ok(fields.has(f), `${s.key}: unknown field ${f}`);
        assert.match(s.key, /^[a-z][a-z0-9_]*$/);
        assert.ok(!seen.has(s.key), `duplicate key ${s.key}`);
        seen.add(s.key);
        assert.ok(types.has(s.type), `${s.key}: bad type ${s.type}`);
        if ("subtype" in s) {
            assert.equal(s.type, "string", `${s.key}: subtype only on strings`);
            assert.ok(subtypes.has(s.subtype), `${s.key}: bad subtype ${s.subtype}`);
        }
        if ("visible" in s) assert.ok(visibilities.has(s.visible));
        if ("required" in s) assert.equal(typeof s.required, "boolean");
        assert.equal(typeof s.description, "string", `${s.key}: needs a description`);
        if ("default" in s) {
            const expected = { string: "string", int32: "number", float: "number", bool: "boolean" }[s.type];
            assert.equal(typeof s.default, expected, `${s.key}: default of the wrong type`);
            if (s.type === "int32") assert.ok(Number.isInteger(s.default));
        }
    }
    // Exactly these settings, with these types and required flags.
    assert.deepEqual(plain(JOB_TYPE.settings.map((s) => [s.key, s.type, s.required === true])), [
        ["paths", "string", true],
        ["shards", "int32", true],
        ["output_dir", "string", true],
        ["gloffuse_exe", "string", false],
        ["extra_args", "string", false],
    ]);
    const byKey = Object.fromEntries(JOB_TYPE.settings.map((s) => [s.key, s]));
    assert.equal(byKey.shards.default, 4);
    assert.deepEqual(plain(byKey.shards.propargs), { min: 1, max: 1000 });
    assert.equal(byKey.output_dir.subtype, "dir_path");
    assert.equal(byKey.gloffuse_exe.default, "gloffuse");
    // The Manager exports JOB_TYPE into its API type (and hashes its JSON for the
    // etag): only plain data, no functions or undefined values.
    (function walk(v, where) {
        assert.ok(v !== undefined && typeof v !== "function", `${where} is not plain data`);
        if (v && typeof v === "object") for (const [k, x] of Object.entries(v)) walk(x, `${where}.${k}`);
    })(JOB_TYPE, "JOB_TYPE");
});

test("compileJob: N blender shard tasks with exact arguments, then a merge that depends on all of them", () => {
    const { compileJob, printed } = load();
    const job = fakeJob(BASE);
    compileJob(job);

    assert.equal(job.tasks.length, 4);
    const [s1, s2, s3, merge] = job.tasks;
    const shards = [s1, s2, s3];
    assert.deepEqual(plain(shards.map((t) => [t.name, t.type])), [
        ["audit-shard-1-of-3", "blender"],
        ["audit-shard-2-of-3", "blender"],
        ["audit-shard-3-of-3", "blender"],
    ]);
    shards.forEach((t, i) => {
        assert.deepEqual(plain(t.commands), [{
            name: "exec",
            parameters: { exe: "/opt/gloffuse/gloffuse", args: shardArgs(i + 1, 3) },
            totalStepCount: 0,
        }]);
        assert.equal(t.dependencies.length, 0, "shards run independently");
    });
    const reportDirs = shards.map((t) => t.commands[0].parameters.args[t.commands[0].parameters.args.indexOf("--report") + 1]);
    assert.equal(new Set(reportDirs).size, 3, "each shard writes its own folder");

    assert.equal(merge.name, "merge-reports");
    assert.equal(merge.type, "misc");
    assert.deepEqual(plain(merge.commands), [{
        name: "exec",
        parameters: { exe: "/opt/gloffuse/gloffuse", args: mergeArgs(3) },
        totalStepCount: 0,
    }]);
    // The very task objects that were added, each once.
    assert.equal(merge.dependencies.length, 3);
    shards.forEach((t, i) => assert.strictEqual(merge.dependencies[i], t));
    assert.ok(printed.some((line) => line.includes("3 shard(s)")));
});

test("compileJob: one shard is 1/1, and the merge lists that one folder", () => {
    const job = compile({ shards: 1 });
    assert.equal(job.tasks.length, 2);
    assert.deepEqual(plain(job.tasks[0].commands[0].parameters.args), shardArgs(1, 1));
    assert.deepEqual(plain(job.tasks[1].commands[0].parameters.args), mergeArgs(1));
    assert.strictEqual(job.tasks[1].dependencies[0], job.tasks[0]);
});

test("compileJob: shards given as a numeric string (API submissions) are accepted", () => {
    const job = compile({ shards: "2" });
    assert.deepEqual(plain(job.tasks.map((t) => t.name)), ["audit-shard-1-of-2", "audit-shard-2-of-2", "merge-reports"]);
});

test("compileJob: paths with spaces stay single arguments, split on ';' and trimmed", () => {
    const out = "/mnt/farm/audit runs/May 6";
    const job = compile({
        paths: " /mnt/farm/My Assets ;/mnt/farm/props/chair v2.blend; ",
        output_dir: out,
        shards: 2,
    });
    const paths = ["/mnt/farm/My Assets", "/mnt/farm/props/chair v2.blend"];
    assert.deepEqual(plain(job.tasks[0].commands[0].parameters.args), shardArgs(1, 2, { out, paths }));
    assert.deepEqual(plain(job.tasks[1].commands[0].parameters.args), shardArgs(2, 2, { out, paths }));
    assert.deepEqual(plain(job.tasks[2].commands[0].parameters.args), mergeArgs(2, out));
});

test("compileJob: extra_args are split like a shell line and go to every shard, not to the merge", () => {
    const extra = ["--fail-on", "creates,error", "--spp", "256", "--fix-dir", "/mnt/farm/fixed copies"];
    const job = compile({ extra_args: `--fail-on creates,error --spp 256 --fix-dir "/mnt/farm/fixed copies"`, shards: 2 });
    assert.deepEqual(plain(job.tasks[0].commands[0].parameters.args), shardArgs(1, 2, { extra }));
    assert.deepEqual(plain(job.tasks[1].commands[0].parameters.args), shardArgs(2, 2, { extra }));
    assert.deepEqual(plain(job.tasks[2].commands[0].parameters.args), mergeArgs(2));
});

test("compileJob: output_dir gets {timestamp}, keeps Windows separators and Flamenco variables", () => {
    let job = compile({ output_dir: "/mnt/farm/audits/{timestamp}/", shards: 1 });
    const out = `/mnt/farm/audits/${TIMESTAMP}`;
    assert.deepEqual(plain(job.tasks[0].commands[0].parameters.args), shardArgs(1, 1, { out }));
    assert.deepEqual(plain(job.tasks[1].commands[0].parameters.args), mergeArgs(1, out));
    assert.equal(job.settings.output_dir, `${out}/`, "the web interface shows the folder used");

    job = compile({ output_dir: "S:\\audits\\run", paths: "S:\\assets", shards: 1 });
    const args = plain(job.tasks[0].commands[0].parameters.args);
    assert.equal(args[args.indexOf("--report") + 1], "S:\\audits\\run\\shard-1");
    assert.equal(args[args.indexOf("--junit") + 1], "S:\\audits\\run\\shard-1.xml");
    assert.equal(args[args.length - 1], "S:\\assets");

    job = compile({ output_dir: "{shared}/audits", paths: "{shared}/assets", shards: 1 });
    assert.deepEqual(plain(job.tasks[0].commands[0].parameters.args),
        shardArgs(1, 1, { out: "{shared}/audits", paths: ["{shared}/assets"] }));
});

test("compileJob: gloffuse_exe defaults to 'gloffuse' when omitted or empty", () => {
    for (const gloffuse_exe of [undefined, ""]) {
        const job = compile({ gloffuse_exe });
        for (const t of job.tasks) assert.equal(t.commands[0].parameters.exe, "gloffuse");
    }
});

function assertRejected(settings, pattern, opts) {
    const { compileJob } = load(opts);
    const job = fakeJob(Object.assign({}, BASE, settings));
    assert.throws(() => compileJob(job), pattern, JSON.stringify(settings));
    assert.equal(job.tasks.length, 0, "no task is added when the settings are refused");
}

test("validation: shards must be a whole number from 1 to 1000", () => {
    for (const shards of [undefined, null, ""]) {
        assertRejected({ shards }, /setting 'shards': required: the number of shard tasks, 1 or more/);
    }
    for (const shards of [0, -1, 2.5, 1001, NaN, "abc", "0", true]) {
        assertRejected({ shards }, /setting 'shards': '.*' is not a whole number from 1 to 1000/);
    }
});

test("validation: paths must be non-empty and absolute (or start with a Flamenco variable)", () => {
    for (const paths of [undefined, "", "   ", 42]) {
        assertRejected({ paths }, /setting 'paths': required: one or more \.blend files or folders, separated by ';'/);
    }
    assertRejected({ paths: " ; ;" }, /setting 'paths': no path in ' ; ;'/);
    assertRejected({ paths: "/mnt/farm/a;assets/b.blend" }, /setting 'paths': 'assets\/b\.blend' is relative/);
    assertRejected({ paths: "-rf" }, /setting 'paths': '-rf' is relative/);
});

test("validation: output_dir must be given and absolute", () => {
    for (const output_dir of [undefined, "", "  "]) {
        assertRejected({ output_dir }, /setting 'output_dir': required: a shared folder/);
    }
    assertRejected({ output_dir: "audits" }, /setting 'output_dir': 'audits' is relative/);
    assertRejected({ output_dir: "{timestamp}" }, new RegExp(`setting 'output_dir': '${TIMESTAMP}' is relative`));
});

test("validation: extra_args may not set what the job sets, and need shellSplit", () => {
    for (const [extra_args, option] of [
        ["--shard 1/2", "--shard"], ["--report=/tmp/x", "--report"], ["--junit a.xml", "--junit"],
        ["--blender /usr/bin/blender", "--blender"], ["--exit-zero", "--exit-zero"],
    ]) {
        assertRejected({ extra_args }, new RegExp(`setting 'extra_args': must not contain ${option}: the job sets it`));
    }
    assertRejected({ extra_args: "--spp 8 -- /other" }, /setting 'extra_args': must not contain '--'/);
    assertRejected({ extra_args: '--fix-dir "/mnt/x' },
        /setting 'extra_args': cannot split '--fix-dir "\/mnt\/x' like a command line: EOF found when expecting closing quote/);
    assertRejected({ extra_args: "--spp 8" }, /setting 'extra_args': needs Flamenco 3\.6 or newer/, { withShellSplit: false });
    // Without extra_args, shellSplit is not needed (Flamenco 3.3 to 3.5).
    const job = compile({ extra_args: "" }, { withShellSplit: false });
    assert.equal(job.tasks.length, 4);
});
