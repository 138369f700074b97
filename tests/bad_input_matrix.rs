//! Bad input through the real `gloffuse` binary: one table, one row per mistake a user can
//! make with a flag or an input file, for every command.
//!
//! Exit codes (docs/GUIDE.md, "Exit codes"):
//! - 0: success;
//! - 1: a check failed (`verify` or `refresh` found a sphere outside the tolerance);
//! - 2: bad input (a flag value, a coefficients file, an output path), or Blender could not
//!   be found, crashed, timed out or wrote nothing.
//!
//! Every row here expects 2. For each row the test checks that:
//! - stderr holds a fragment that names the input and/or says what would be right, and no
//!   panic;
//! - nothing is created or left half-written: the case's directory (a fresh temporary
//!   directory whose name has spaces and non-ASCII characters, also the working directory)
//!   holds exactly the files the case put there, unchanged, and each output the case named
//!   (`--out`, `--table`, `--script`, `--blend`, `--report`) does not exist;
//! - bad input fails fast: commands that need Blender get `--blender /nonexistent/blender
//!   --no-provision`, and a row fails if the error is about that Blender instead of the
//!   input (only the one row whose input is fine expects it), and no Blender run directory
//!   appears in the cache (`XDG_CACHE_HOME` points at a temporary directory).
//!
//! Tier: fast (no Blender; `scripts/test.sh --fast` runs it).

mod common;

use serde_json::{Value, json};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// What the Blender-needing rows pass: a Blender that does not exist, and no install.
const NO_BLENDER: [&str; 3] = ["--blender", "/nonexistent/blender", "--no-provision"];

/// One row. In `args`, `stderr` and `outputs`, `@/NAME` stands for `NAME` in the case's
/// directory.
struct Case {
    args: Vec<String>,
    /// Files (or, for a name ending in `/`, directories) made before the run.
    files: Vec<(&'static str, Vec<u8>)>,
    code: i32,
    stderr: Vec<String>,
    /// Outputs that must not exist afterwards.
    outputs: Vec<&'static str>,
}

fn case(args: &[&str]) -> Case {
    Case {
        args: args.iter().map(|a| a.to_string()).collect(),
        files: Vec::new(),
        code: 2,
        stderr: Vec::new(),
        outputs: Vec::new(),
    }
}

impl Case {
    /// Adds `--blender /nonexistent/blender --no-provision`.
    fn no_blender(mut self) -> Self {
        self.args.extend(NO_BLENDER.map(String::from));
        self
    }
    fn file(mut self, name: &'static str, contents: impl Into<Vec<u8>>) -> Self {
        self.files.push((name, contents.into()));
        self
    }
    fn dir(self, name: &'static str) -> Self {
        self.file(name, Vec::new())
    }
    fn says(mut self, fragments: &[&str]) -> Self {
        self.stderr.extend(fragments.iter().map(|f| f.to_string()));
        self
    }
    fn writes_nothing_to(mut self, outputs: &[&'static str]) -> Self {
        self.outputs.extend(outputs);
        self
    }
}

/// The blender-4 preset as JSON, to be damaged one field at a time.
fn preset() -> Value {
    serde_json::from_str(include_str!("../presets/blender-4.json")).unwrap()
}

fn edited(edit: impl FnOnce(&mut Value)) -> Vec<u8> {
    let mut v = preset();
    edit(&mut v);
    serde_json::to_vec_pretty(&v).unwrap()
}

/// The preset with GGX's curve replaced (and its "degree" field to match).
fn ggx_numerator(numerator: Value) -> Vec<u8> {
    edited(|v| {
        let ggx = &mut v["distributions"]["ggx"];
        ggx["degree"] = json!(numerator.as_array().unwrap().len() - 1);
        ggx["curve"]["numerator"] = numerator;
    })
}

fn cases() -> Vec<Case> {
    let text = include_str!("../presets/blender-4.json");
    let first_coefficient = "-0.21170505258318373";
    assert!(text.contains(first_coefficient), "the preset changed");
    vec![
        // --- albedo -------------------------------------------------------------------
        case(&["albedo", "-d", "phong", "-r", "0.5"]).says(&[
            "invalid distribution 'phong'",
            "beckmann, ggx, ashikhmin-shirley",
        ]),
        case(&["albedo", "-d", "ggx", "-r", "1.5"])
            .says(&["invalid roughness '1.5'", "expected a number from 0 to 1"]),
        case(&["albedo", "-d", "ggx", "-r", "0.5", "--mu", "0"])
            .says(&["invalid view cosine '0'", "(0, 1]"]),
        case(&[
            "albedo",
            "-d",
            "ggx",
            "-r",
            "0.5",
            "--blender-version",
            "2.79",
        ])
        .says(&["'2.79'", "Blender 3.0 or later"]),
        case(&["albedo", "-d", "ggx"]).says(&["--roughness R"]),
        case(&["albedo", "-d", "ggx", "--table", "@/t.csv", "--grid", "1"])
            .says(&["'1' for '--grid", "2..=4096"])
            .writes_nothing_to(&["@/t.csv"]),
        case(&[
            "albedo", "-d", "ggx", "--table", "@/t.csv", "--grid", "100000",
        ])
        .says(&["'100000' for '--grid", "2..=4096"])
        .writes_nothing_to(&["@/t.csv"]),
        case(&[
            "albedo",
            "-d",
            "ggx",
            "--grid",
            "2",
            "--table",
            "@/no dir/t.csv",
        ])
        .says(&[
            "cannot write @/no dir/t.csv",
            "the directory @/no dir does not exist",
        ])
        .writes_nothing_to(&["@/no dir/t.csv"]),
        case(&["albedo", "-d", "ggx", "--grid", "2", "--table", "@/a dir"])
            .dir("a dir/")
            .says(&["cannot write @/a dir", "is a directory; give a file name"]),
        // --- fit ----------------------------------------------------------------------
        case(&[
            "fit", "-d", "ggx", "-p", "0.5:85", "-p", "1:59", "--degree", "9", "--out", "@/c.json",
        ])
        .says(&["invalid --degree '9'", "from 2 to 8"])
        .writes_nothing_to(&["@/c.json"]),
        case(&[
            "fit",
            "--from",
            "integrator",
            "--degree",
            "1",
            "--out",
            "@/c.json",
        ])
        .says(&["invalid --degree '1'", "from 2 to 8"])
        .writes_nothing_to(&["@/c.json"]),
        case(&["fit", "--from", "magic", "--out", "@/c.json"])
            .says(&["'magic' for '--from", "integrator"])
            .writes_nothing_to(&["@/c.json"]),
        case(&[
            "fit",
            "--from",
            "integrator",
            "--target",
            "middle",
            "--out",
            "@/c.json",
        ])
        .says(&["'middle' for '--target", "mean, center"])
        .writes_nothing_to(&["@/c.json"]),
        case(&[
            "fit",
            "-d",
            "ggx",
            "-p",
            "0.5:85",
            "-p",
            "1:59",
            "--weighting",
            "squared",
        ])
        .says(&["'squared' for '--weighting", "absolute, relative"]),
        case(&["fit", "-d", "ggx", "-p", "2:50", "-p", "1:59"]).says(&["roughness outside [0, 1]"]),
        case(&["fit", "--from", "integrator", "-d", "ggx"]).says(&[
            "invalid --distribution 'ggx'",
            "nothing with --from integrator",
        ]),
        // Two points that pull the cubic below zero before r = 1.
        case(&[
            "fit",
            "-d",
            "ggx",
            "-p",
            "0.5:30",
            "-p",
            "1:5",
            "--weighting",
            "absolute",
            "--out",
            "@/c.json",
        ])
        .says(&[
            "@/c.json",
            "ggx: f(",
            "must stay above 0 on roughness [0, 1]",
        ])
        .writes_nothing_to(&["@/c.json"]),
        case(&[
            "fit",
            "-d",
            "ggx",
            "-p",
            "0.5:85",
            "-p",
            "1:59",
            "--out",
            "@/no dir/c.json",
        ])
        .says(&[
            "cannot write @/no dir/c.json",
            "the directory @/no dir does not exist",
        ])
        .writes_nothing_to(&["@/no dir/c.json"]),
        case(&[
            "fit", "-d", "ggx", "-p", "0.5:85", "-p", "1:59", "--out", "@/a dir",
        ])
        .dir("a dir/")
        .says(&["cannot write @/a dir", "is a directory"]),
        // --- coefficient files ----------------------------------------------------------
        case(&["coefficients", "show", "@/c.json"])
            .file("c.json", "{ not json")
            .says(&["coefficients @/c.json: not valid JSON"]),
        case(&["coefficients", "show", "@/c.json"])
            .file("c.json", &text.as_bytes()[..text.len() / 2])
            .says(&["coefficients @/c.json: not valid JSON", "EOF"]),
        case(&["coefficients", "show", "@/c.json"])
            .file(
                "c.json",
                edited(|v| v["format"] = json!("gloffuse-coefficient")),
            )
            .says(&[
                "@/c.json: not a coefficients file",
                "\"gloffuse-coefficients\"",
            ]),
        case(&["coefficients", "show", "@/c.json"])
            .file("c.json", edited(|v| v["format_version"] = json!(2)))
            .says(&[
                "@/c.json: format_version 2 is not supported",
                "reads format_version 1",
            ]),
        case(&["coefficients", "show", "@/c.json"])
            .file("c.json", edited(|v| v["format_version"] = json!("1")))
            .says(&[
                "@/c.json",
                "\"format_version\" is \"1\"; expected the number 1",
            ]),
        // JSON has no NaN or infinity; a number too big for f64 is refused by the parser.
        case(&["coefficients", "show", "@/c.json"])
            .file("c.json", text.replacen(first_coefficient, "1e400", 1))
            .says(&["coefficients @/c.json: not valid JSON: number out of range"]),
        case(&["coefficients", "show", "@/c.json"])
            .file("c.json", ggx_numerator(json!([100.0, 0.0, "NaN", 1.0])))
            .says(&[
                "@/c.json: malformed",
                "invalid type: string \"NaN\", expected f64",
            ]),
        case(&["coefficients", "show", "@/c.json"])
            .file("c.json", ggx_numerator(json!([100.0, 0.0, null])))
            .says(&["@/c.json: malformed", "invalid type: null, expected f64"]),
        // A negative r² term: f(r) = 100 − 100 r² reaches 0 at r = 1.
        case(&["coefficients", "show", "@/c.json"])
            .file("c.json", ggx_numerator(json!([100.0, 0.0, -100.0])))
            .says(&[
                "@/c.json: ggx: f(1) = 0",
                "must stay above 0 on roughness [0, 1]",
            ]),
        // f(r) = 100 − 150 r² crosses 0 inside [0, 1]: the first roughness where it fails.
        case(&["coefficients", "show", "@/c.json"])
            .file("c.json", ggx_numerator(json!([100.0, 0.0, -150.0])))
            .says(&["@/c.json: ggx: f(0.817) = -0.12", "must stay above 0"]),
        // An absurd coefficient: refused, and the message stays short.
        case(&["coefficients", "show", "@/c.json"])
            .file("c.json", ggx_numerator(json!([100.0, 0.0, -1e308])))
            .says(&["@/c.json: ggx: f(0.001) = -1.000e302", "must stay above 0"]),
        case(&["coefficients", "show", "@/c.json"])
            .file("c.json", ggx_numerator(json!([100.0, 0.0, 1e308, 1e308])))
            .says(&["@/c.json: ggx: f(", ") = inf", "must stay above 0"]),
        case(&["coefficients", "show", "@/c.json"])
            .file(
                "c.json",
                ggx_numerator(json!([100.0, 0.0, 1, 1, 1, 1, 1, 1, 1, 1])),
            )
            .says(&["@/c.json: ggx: degree 9 is above the maximum 8"]),
        case(&["coefficients", "show", "@/c.json"])
            .file(
                "c.json",
                edited(|v| v["distributions"]["ggx"]["degree"] = json!(99)),
            )
            .says(&["@/c.json: ggx: \"degree\" is 99, but the curve has degree 6"]),
        case(&["coefficients", "show", "@/c.json"])
            .file(
                "c.json",
                edited(|v| {
                    let d = v["distributions"].as_object_mut().unwrap();
                    let ggx = d.remove("ggx").unwrap();
                    d.insert("phong".into(), ggx);
                }),
            )
            .says(&[
                "@/c.json: malformed",
                "unknown variant `phong`",
                "`ashikhmin-shirley`",
            ]),
        case(&["coefficients", "show", "@/c.json"])
            .file("c.json", edited(|v| v["distributions"] = json!({})))
            .says(&["@/c.json: holds no distributions"]),
        case(&["coefficients", "show", "@/c.json"])
            .file("c.json", ggx_numerator(json!([100.0, 5.0, -20.0])))
            .says(&["@/c.json: ggx: the r¹ coefficient must be 0"]),
        // Unreadable: a directory where the file should be (tests run as root, so a mode
        // of 000 would not stop a read), and a path into a directory that does not exist.
        case(&["coefficients", "show", "@/c.json"])
            .dir("c.json/")
            .says(&["cannot read @/c.json", "Is a directory"]),
        case(&["coefficients", "show", "@/no dir/c.json"]).says(&[
            "coefficients @/no dir/c.json: no such preset or file",
            "seed, blender-3, blender-4",
        ]),
        // --- generate -----------------------------------------------------------------
        case(&["generate"]).no_blender().says(&[
            "(no output)",
            "--script OUT.py, --blend OUT.blend, --into EXISTING.blend, --extension OUT.zip or \
             --addon OUT.zip",
        ]),
        case(&["generate", "--addon", "@/gloffuse.tar"])
            .no_blender()
            .says(&[
                "invalid --addon '@/gloffuse.tar'",
                "a file name ending in .zip",
            ])
            .writes_nothing_to(&["@/gloffuse.tar"]),
        case(&["generate", "--extension", "@/g.zip", "--addon", "@/g.zip"])
            .no_blender()
            .says(&[
                "invalid --addon '@/g.zip'",
                "a file other than the --extension",
            ])
            .writes_nothing_to(&["@/g.zip"]),
        case(&["generate", "--extension", "@/gloffuse.tar"])
            .no_blender()
            .says(&[
                "invalid --extension '@/gloffuse.tar'",
                "a file name ending in .zip",
            ])
            .writes_nothing_to(&["@/gloffuse.tar"]),
        case(&[
            "generate",
            "--extension",
            "@/g.zip",
            "--into",
            "@/scene.blend",
        ])
        .no_blender()
        .file("scene.blend", "BLENDER-v405")
        .says(&["'--extension <OUT.zip>' cannot be used with '--into <EXISTING.blend>'"])
        .writes_nothing_to(&["@/g.zip", "@/scene.blend1"]),
        case(&["generate", "--extension", "@/no dir/g.zip"])
            .no_blender()
            .says(&[
                "cannot write @/no dir/g.zip",
                "the directory @/no dir does not exist",
            ])
            .writes_nothing_to(&["@/no dir/g.zip"]),
        case(&["generate", "--script", "@/no dir/g.py"])
            .says(&[
                "cannot write @/no dir/g.py",
                "the directory @/no dir does not exist",
            ])
            .writes_nothing_to(&["@/no dir/g.py"]),
        case(&["generate", "--script", "@/a dir"])
            .dir("a dir/")
            .says(&["cannot write @/a dir", "is a directory"]),
        case(&["generate", "--blend", "@/no dir/g.blend"])
            .no_blender()
            .says(&[
                "cannot write @/no dir/g.blend",
                "the directory @/no dir does not exist",
            ])
            .writes_nothing_to(&["@/no dir/g.blend"]),
        case(&["generate", "--blend", "@/a dir"])
            .no_blender()
            .dir("a dir/")
            .says(&["cannot write @/a dir", "is a directory"]),
        // One bad output: the other is not written either.
        case(&[
            "generate",
            "--script",
            "@/g.py",
            "--blend",
            "@/no dir/g.blend",
        ])
        .no_blender()
        .says(&["the directory @/no dir does not exist"])
        .writes_nothing_to(&["@/g.py", "@/no dir/g.blend"]),
        case(&["generate", "--into", "@/missing.blend"])
            .no_blender()
            .says(&[
                "invalid --into '@/missing.blend'",
                "an existing .blend file",
            ])
            .writes_nothing_to(&["@/missing.blend", "@/missing.blend1"]),
        case(&["generate", "--into", "@/notes.blend"])
            .no_blender()
            .file("notes.blend", "just some notes\n")
            .says(&[
                "invalid --into '@/notes.blend'",
                "does not start with a .blend header",
            ])
            .writes_nothing_to(&["@/notes.blend1"]),
        case(&[
            "generate",
            "--blend",
            "@/g.blend",
            "--into",
            "@/scene.blend",
        ])
        .no_blender()
        .file("scene.blend", "BLENDER-v405")
        .says(&["'--blend <OUT.blend>' cannot be used with '--into <EXISTING.blend>'"])
        .writes_nothing_to(&["@/g.blend", "@/scene.blend1"]),
        case(&[
            "generate",
            "--coefficients",
            "@/c.json",
            "--blend",
            "@/g.blend",
        ])
        .no_blender()
        .file("c.json", "[1, 2")
        .says(&["coefficients @/c.json: not valid JSON"])
        .writes_nothing_to(&["@/g.blend"]),
        case(&[
            "generate",
            "--coefficients",
            "blender-5",
            "--script",
            "@/g.py",
        ])
        .says(&[
            "coefficients blender-5: no such preset or file",
            "seed, blender-3, blender-4",
        ])
        .writes_nothing_to(&["@/g.py"]),
        case(&["generate", "--script", "@/g.py", "--color-model", "pink"])
            .says(&["'pink'", "exact", "physical"])
            .writes_nothing_to(&["@/g.py"]),
        case(&["generate", "--blend", "@/g.blend", "--timeout", "0"])
            .no_blender()
            .says(&["'0' for '--timeout", "1..=86400"])
            .writes_nothing_to(&["@/g.blend"]),
        case(&[
            "generate",
            "--engine",
            "eevee",
            "--mode",
            "anisotropic",
            "--script",
            "@/g.py",
        ])
        .says(&[
            "invalid --mode 'anisotropic'",
            "EEVEE renders an anisotropic Glossy as an isotropic one",
        ])
        .writes_nothing_to(&["@/g.py"]),
        case(&[
            "generate", "--engine", "eevee", "--mode", "glass", "--script", "@/g.py",
        ])
        .says(&[
            "invalid --mode 'glass'",
            "Cycles' Glass and Refraction BSDFs",
        ])
        .writes_nothing_to(&["@/g.py"]),
        // --- verify -------------------------------------------------------------------
        case(&["verify", "--mode", "glass", "--engine", "eevee"])
            .no_blender()
            .says(&[
                "invalid --engine 'eevee'",
                "cycles with --mode glass",
                "EEVEE renders glass its own way",
            ]),
        case(&["verify", "--mode", "glass", "--color", "1,0.5,0.5"])
            .no_blender()
            .says(&[
                "invalid --color '1,0.5,0.5'",
                "1,1,1 with --mode glass",
                "tints light at every surface",
            ]),
        case(&["verify", "--mode", "glass", "--color-model", "physical"])
            .no_blender()
            .says(&[
                "invalid --color-model 'physical'",
                "exact with --mode glass",
            ]),
        case(&["verify", "--mode", "glass", "--ior", "1.5,1.5"])
            .no_blender()
            .says(&["invalid --ior '1.5'", "each index once, from 1 to 3"]),
        case(&["verify", "--mode", "glass", "--anisotropy", "0.5"])
            .no_blender()
            .says(&[
                "invalid --anisotropy '0.5'",
                "--anisotropy goes with --mode anisotropic",
            ]),
        case(&["verify", "--ior", "1.5"]).no_blender().says(&[
            "invalid --ior '1.5'",
            "--ior goes with --mode layered or glass",
        ]),
        case(&["verify", "--anisotropy", "0.5"])
            .no_blender()
            .says(&[
                "invalid --anisotropy '0.5'",
                "--anisotropy goes with --mode anisotropic",
            ]),
        case(&["verify", "--mode", "anisotropic", "--anisotropy", "0.5,1.2"])
            .no_blender()
            .says(&["invalid --anisotropy '1.2'", "from -0.99 to 0.99"]),
        case(&[
            "verify",
            "--mode",
            "anisotropic",
            "--anisotropy",
            "-0.5,-0.5",
        ])
        .no_blender()
        .says(&["invalid --anisotropy '-0.5'", "each anisotropy once"]),
        case(&["verify", "--mode", "anisotropic", "--engine", "eevee"])
            .no_blender()
            .says(&[
                "invalid --engine 'eevee'",
                "cycles with --mode anisotropic",
                "EEVEE renders an anisotropic Glossy as an isotropic one",
            ]),
        case(&[
            "verify",
            "--mode",
            "anisotropic",
            "--color-model",
            "physical",
        ])
        .no_blender()
        .says(&[
            "invalid --color-model 'physical'",
            "exact with --mode anisotropic",
        ]),
        case(&["verify", "-r", ""])
            .no_blender()
            .says(&["invalid roughness ''", "a number from 0 to 1"]),
        case(&["verify", "-r", "0.5,1.5"])
            .no_blender()
            .says(&["invalid roughness '1.5'"]),
        case(&["verify", "-r", "0.5,0.5"])
            .no_blender()
            .says(&["invalid --roughness '0.5'", "each roughness once"]),
        case(&["verify", "-d", "phong"])
            .no_blender()
            .says(&["invalid distribution 'phong'"]),
        case(&[
            "verify",
            "--coefficients",
            "seed",
            "-d",
            "ashikhmin-shirley",
        ])
        .no_blender()
        .says(&[
            "invalid --distribution 'ashikhmin-shirley'",
            "the coefficients 'seed' hold: beckmann, ggx",
        ]),
        case(&["verify", "--ior", "1.5"])
            .no_blender()
            .says(&["invalid --ior '1.5'", "--ior goes with --mode layered"]),
        case(&["verify", "--mode", "layered", "--ior", "0.5"])
            .no_blender()
            .says(&["'0.5' is not an index of refraction from 1 to 3"]),
        case(&["verify", "--mode", "layered", "--ior", "1.5,1.5"])
            .no_blender()
            .says(&["invalid --ior '1.5'", "each index once"]),
        case(&["verify", "--spp", "0"])
            .no_blender()
            .says(&["'0' for '--spp", "1..=65536"]),
        case(&["verify", "--spp", "10000000"])
            .no_blender()
            .says(&["'10000000' for '--spp", "1..=65536"]),
        case(&["verify", "--resolution", "0"])
            .no_blender()
            .says(&["'0' for '--resolution", "8..=1024"]),
        case(&["verify", "--resolution", "100000"])
            .no_blender()
            .says(&["'100000' for '--resolution", "8..=1024"]),
        case(&["verify", "--tolerance", "0"])
            .no_blender()
            .says(&["invalid tolerance '0'", "above 0 and at most 100"]),
        case(&["verify", "--timeout", "0"])
            .no_blender()
            .says(&["'0' for '--timeout", "1..=86400"]),
        case(&["verify", "--coefficients", "@/c.json", "-r", "1"])
            .no_blender()
            .file("c.json", ggx_numerator(json!([100.0, 0.0, -100.0])))
            .says(&["coefficients @/c.json: ggx: f(1) = 0", "must stay above 0"]),
        case(&["verify", "--coefficients", "@/c.json"])
            .no_blender()
            .dir("c.json/")
            .says(&["cannot read @/c.json"]),
        case(&["verify", "--report", "@/notes.txt"])
            .no_blender()
            .file("notes.txt", "notes\n")
            .says(&[
                "cannot write @/notes.txt",
                "a report needs a directory, and this is a file",
            ]),
        case(&["verify", "--report", "@/notes.txt/report"])
            .no_blender()
            .file("notes.txt", "notes\n")
            .says(&[
                "cannot write @/notes.txt/report",
                "a report needs a directory, but @/notes.txt is a file",
            ]),
        // The one row whose input is fine: then the missing Blender is what is reported, and
        // the report directory is not made.
        case(&["verify", "-r", "0.5", "--report", "@/report"])
            .no_blender()
            .says(&["--blender /nonexistent/blender: no such file"])
            .writes_nothing_to(&["@/report"]),
        // --- refresh ------------------------------------------------------------------
        case(&["refresh", "--out", "@/no dir/c.json"])
            .no_blender()
            .says(&[
                "cannot write @/no dir/c.json",
                "the directory @/no dir does not exist",
            ])
            .writes_nothing_to(&["@/no dir/c.json"]),
        case(&["refresh", "--out", "@/a dir"])
            .no_blender()
            .dir("a dir/")
            .says(&["cannot write @/a dir", "is a directory"]),
        case(&["refresh", "--degree", "9"])
            .no_blender()
            .says(&["'9' for '--degree", "2..=8"])
            .writes_nothing_to(&["@/coefficients.json"]),
        case(&["refresh", "--degree", "1"])
            .no_blender()
            .says(&["'1' for '--degree", "2..=8"])
            .writes_nothing_to(&["@/coefficients.json"]),
        case(&["refresh", "--spp", "0"])
            .no_blender()
            .says(&["'0' for '--spp", "1..=65536"])
            .writes_nothing_to(&["@/coefficients.json"]),
        case(&["refresh", "--resolution", "100000"])
            .no_blender()
            .says(&["'100000' for '--resolution", "8..=1024"]),
        case(&["refresh", "--timeout", "0"])
            .no_blender()
            .says(&["'0' for '--timeout", "1..=86400"]),
        // --- bench --------------------------------------------------------------------
        case(&["bench", "-r", "2"])
            .no_blender()
            .says(&["invalid roughness '2'"]),
        case(&["bench", "--spp", "0"])
            .no_blender()
            .says(&["'0' for '--spp", "1..=65536"]),
    ]
}

/// Every file and directory under `root`, relative, with the contents of files.
fn snapshot(root: &Path) -> BTreeMap<PathBuf, Option<Vec<u8>>> {
    let mut all = BTreeMap::new();
    let mut stack = vec![root.to_path_buf()];
    while let Some(dir) = stack.pop() {
        for entry in std::fs::read_dir(&dir).unwrap() {
            let path = entry.unwrap().path();
            let rel = path.strip_prefix(root).unwrap().to_path_buf();
            if path.is_dir() {
                stack.push(path);
                all.insert(rel, None);
            } else {
                all.insert(rel, Some(std::fs::read(&path).unwrap()));
            }
        }
    }
    all
}

fn run_case(case: &Case) -> Result<(), String> {
    let dir = tempfile::Builder::new()
        .prefix("gloffuse bad input Ünïcode ☀ ")
        .tempdir()
        .unwrap();
    let cache = tempfile::Builder::new()
        .prefix("gloffuse cache ")
        .tempdir()
        .unwrap();
    let at = |s: &str| s.replace("@/", &format!("{}/", dir.path().display()));
    for (name, contents) in &case.files {
        let path = dir.path().join(name);
        if name.ends_with('/') {
            std::fs::create_dir_all(&path).unwrap();
        } else {
            std::fs::write(&path, contents).unwrap();
        }
    }
    let before = snapshot(dir.path());
    let args: Vec<String> = case.args.iter().map(|a| at(a)).collect();
    let out = common::gloffuse()
        .args(&args)
        .current_dir(dir.path())
        .env("XDG_CACHE_HOME", cache.path())
        .env_remove("GLOFFUSE_BLENDER")
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    let mut problems = Vec::new();
    if out.status.code() != Some(case.code) {
        problems.push(format!(
            "exit {:?}, expected {}",
            out.status.code(),
            case.code
        ));
    }
    for fragment in &case.stderr {
        if !stderr.contains(&at(fragment)) {
            problems.push(format!("stderr lacks {:?}", at(fragment)));
        }
    }
    if stderr.contains("panicked") {
        problems.push("panicked".into());
    }
    let expects_blender = case
        .stderr
        .iter()
        .any(|f| f.contains("/nonexistent/blender"));
    if !expects_blender && stderr.contains("/nonexistent/blender") {
        problems.push("the bad input was not detected before Blender was looked for".into());
    }
    if stderr.len() > 1200 {
        problems.push(format!("stderr is {} bytes long", stderr.len()));
    }
    if !out.stdout.is_empty() {
        problems.push(format!(
            "stdout is not empty: {}",
            String::from_utf8_lossy(&out.stdout)
        ));
    }
    let after = snapshot(dir.path());
    if after != before {
        let names = |s: &BTreeMap<PathBuf, Option<Vec<u8>>>| s.keys().cloned().collect::<Vec<_>>();
        problems.push(format!(
            "the directory changed: before {:?}, after {:?} (or a file's contents changed)",
            names(&before),
            names(&after)
        ));
    }
    for output in &case.outputs {
        let path = PathBuf::from(at(output));
        if path.symlink_metadata().is_ok() {
            problems.push(format!("{} exists", path.display()));
        }
    }
    if cache.path().join("gloffuse/runs").exists() {
        problems.push("a Blender run directory was made".into());
    }
    if problems.is_empty() {
        Ok(())
    } else {
        Err(format!(
            "gloffuse {}\n  {}\n  stderr: {}",
            args.join(" "),
            problems.join("\n  "),
            stderr.trim_end().replace('\n', "\n          ")
        ))
    }
}

#[test]
fn bad_input_exits_2_names_the_input_and_leaves_nothing() {
    let cases = cases();
    assert!(cases.len() >= 30, "{} cases", cases.len());
    let failures: Vec<String> = cases.iter().filter_map(|c| run_case(c).err()).collect();
    assert!(
        failures.is_empty(),
        "{} of {} cases failed:\n\n{}",
        failures.len(),
        cases.len(),
        failures.join("\n\n")
    );
}
