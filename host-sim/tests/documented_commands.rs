//! Every command line documented in `README.md` and `docs/*.md`, run through the built
//! `dexter` binary and compared with the output blessed on purpose.
//!
//! The commands are **extracted from the documents themselves** (so the docs and this test
//! cannot drift apart): in fenced code blocks, every line that starts with
//! `cargo run --release` (the arguments after `--`), `$ dexter` or `dexter`, with `\`
//! continuations joined and trailing `# comments` dropped. They run in document order
//! (`README.md`, then `docs/*.md` by name; a repeated line runs once) in one scratch
//! directory holding a link to `scenes/`, as a user following the docs from the workspace
//! root would run them: a later command may rely on a directory an earlier one created.
//!
//! For each command the exit status, stdout, stderr and every file it wrote (new or
//! changed in the scratch directory: SVG, PNG, CSV) are compared with
//! `host-sim/tests/documented/<command>.txt`. Files are compared by length and a 64-bit
//! FNV-1a hash of their exact bytes (SVG text and PNG bytes are deterministic). Timings are
//! masked: the numbers after `wall time`, `wall`, `wall_time_s":` (any key ending so), `steps/s`,
//! `"steps_per_wall_second":` and the HIL instruction counts; the scratch directory's path
//! is shown as `<ROOT>`. Outputs longer than [`MAX_SHOWN_LINES`] lines are compared by
//! hash, with their first and last lines shown.
//!
//! Lines with `--hil` form a separate group (`documented/hil/`): they need QEMU and the
//! `thumbv7em-none-eabihf` target (`scripts/test.sh` installs both) and build the firmware;
//! their output changes with the firmware protocol, so they are re-blessed on their own.
//!
//! Bless (after a deliberate change of output): `DEXTER_BLESS=1 cargo test -p dexter-sim
//! --test documented_commands`. On a mismatch the actual case file is written to
//! `target/tmp/documented-commands/<group>/actual/` and the scratch directory is kept.

use std::collections::BTreeMap;
use std::io::Read;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant, SystemTime};

/// Longest stdout or stderr (in lines) kept verbatim in a case file.
const MAX_SHOWN_LINES: usize = 400;
/// First lines shown of a longer output.
const HEAD_LINES: usize = 30;
/// Last lines shown of a longer output.
const TAIL_LINES: usize = 10;
/// Longest a documented command may run.
const COMMAND_TIMEOUT: Duration = Duration::from_secs(600);

fn workspace() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("..")
        .canonicalize()
        .expect("workspace root")
}

/// One documented command line.
#[derive(Clone, Debug, PartialEq)]
struct Case {
    /// The document it was found in (relative to the workspace).
    doc: String,
    /// The line as written (continuations joined, comment dropped).
    line: String,
    /// The binary's arguments.
    args: Vec<String>,
}

impl Case {
    fn hil(&self) -> bool {
        self.args.iter().any(|a| a == "--hil")
    }

    /// A file name for the case: the arguments, sanitized and cut, and a hash of the line.
    fn slug(&self) -> String {
        let joined = if self.args.is_empty() {
            "default".to_string()
        } else {
            self.args.join("_")
        };
        let mut s: String = joined
            .chars()
            .map(|c| {
                if c.is_ascii_alphanumeric() || "._=-".contains(c) {
                    c
                } else {
                    '_'
                }
            })
            .collect();
        s.truncate(90);
        format!("{s}-{:08x}", fnv64(self.args.join(" ").as_bytes()) as u32)
    }
}

/// The arguments of a documented command line, or None if the line is not one.
fn args_of(line: &str) -> Option<Vec<String>> {
    let line = line.trim();
    let rest = if let Some(r) = line.strip_prefix("cargo run --release") {
        match r.trim().strip_prefix("--") {
            Some(args) => args,
            None if r.trim().is_empty() => "",
            None => return None,
        }
    } else if let Some(r) = line.strip_prefix("$ dexter ") {
        r
    } else {
        line.strip_prefix("dexter ")?
    };
    assert!(
        !rest.contains(['"', '\'', '|', '<', '>', '$', '`']),
        "documented command needs a shell this test does not emulate: {line}"
    );
    Some(rest.split_whitespace().map(str::to_string).collect())
}

/// The documented commands of one document, in order.
fn extract(doc: &str, text: &str) -> Vec<Case> {
    let mut cases = Vec::new();
    let mut in_code = false;
    let mut pending = String::new();
    for raw in text.lines() {
        if raw.trim_start().starts_with("```") {
            in_code = !in_code;
            pending.clear();
            continue;
        }
        if !in_code {
            continue;
        }
        let mut line = raw.trim().to_string();
        if !pending.is_empty() {
            line = format!("{pending} {line}");
            pending.clear();
        }
        if let Some(head) = line.strip_suffix('\\') {
            pending = head.trim_end().to_string();
            continue;
        }
        let line = match line.find(" #") {
            Some(i) => line[..i].trim_end().to_string(),
            None => line,
        };
        if let Some(args) = args_of(&line) {
            cases.push(Case {
                doc: doc.to_string(),
                line,
                args,
            });
        }
    }
    cases
}

/// README.md, then docs/*.md by name; a repeated command runs once.
fn documented_commands() -> Vec<Case> {
    let root = workspace();
    let mut docs = vec![PathBuf::from("README.md")];
    let mut more: Vec<PathBuf> = std::fs::read_dir(root.join("docs"))
        .expect("docs/")
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "md"))
        .map(|p| PathBuf::from("docs").join(p.file_name().unwrap()))
        .collect();
    more.sort();
    docs.extend(more);
    let mut cases: Vec<Case> = Vec::new();
    for doc in docs {
        let text = std::fs::read_to_string(root.join(&doc)).expect("doc readable");
        for c in extract(&doc.display().to_string(), &text) {
            if !cases.iter().any(|k| k.args == c.args) {
                cases.push(c);
            }
        }
    }
    cases
}

fn fnv64(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325u64, |h, &b| {
        (h ^ u64::from(b)).wrapping_mul(0x0000_0100_0000_01b3)
    })
}

/// Markers after which a number is a timing (or, under HIL, an instruction count).
const MASKED_AFTER: [&str; 7] = [
    // also `"planner_wall_time_s":` (the arm)
    "wall_time_s\":",
    "wall time",
    "wall ",
    "steps/s",
    "\"steps_per_wall_second\":",
    "instr min/mean/max",
    "\"step_instructions_",
];

/// `text` with every number that follows a marker of [`MASKED_AFTER`] replaced by `<T>`.
fn mask(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    let mut rest = text;
    'outer: while !rest.is_empty() {
        for m in MASKED_AFTER {
            if let Some(after) = rest.strip_prefix(m) {
                out.push_str(m);
                // a JSON key's tail up to its colon (`"step_instructions_max": 291`)
                let (key_tail, after) = match m.ends_with('_') {
                    true => after.split_at(after.find(':').map_or(0, |i| i + 1)),
                    false => ("", after),
                };
                out.push_str(key_tail);
                let trimmed = after.trim_start_matches(' ');
                out.push_str(&after[..after.len() - trimmed.len()]);
                let num_len = trimmed
                    .find(|c: char| !(c.is_ascii_digit() || ".eE+-/".contains(c)))
                    .unwrap_or(trimmed.len());
                if num_len > 0 && trimmed.starts_with(|c: char| c.is_ascii_digit() || c == '-') {
                    out.push_str("<T>");
                    rest = &trimmed[num_len..];
                } else {
                    rest = trimmed;
                }
                continue 'outer;
            }
        }
        let c = rest.chars().next().unwrap();
        out.push(c);
        rest = &rest[c.len_utf8()..];
    }
    out
}

/// A stream as shown in a case file: verbatim, or its head and hash when long.
fn shown(name: &str, bytes: &[u8], root: &Path) -> String {
    let text = String::from_utf8_lossy(bytes);
    let mut text = mask(&text);
    for r in [root.to_path_buf(), root.canonicalize().unwrap_or_default()] {
        let r = r.display().to_string();
        if !r.is_empty() {
            text = text.replace(&r, "<ROOT>");
        }
    }
    let lines = text.lines().count();
    if lines <= MAX_SHOWN_LINES {
        return format!("--- {name}\n{text}");
    }
    let all: Vec<&str> = text.lines().collect();
    format!(
        "--- {name} ({lines} lines, {} bytes after masking, fnv64 {:016x}; the first {HEAD_LINES} and the last {TAIL_LINES})\n{}\n...\n{}\n",
        text.len(),
        fnv64(text.as_bytes()),
        all[..HEAD_LINES].join("\n"),
        all[lines - TAIL_LINES..].join("\n")
    )
}

/// (length, hash, modification time) of a file.
type Stamp = (u64, u64, Option<SystemTime>);

/// Every file under `dir` (not following the `scenes` link).
fn snapshot(dir: &Path) -> BTreeMap<PathBuf, Stamp> {
    fn walk(base: &Path, dir: &Path, out: &mut BTreeMap<PathBuf, Stamp>) {
        let Ok(entries) = std::fs::read_dir(dir) else {
            return;
        };
        for e in entries.flatten() {
            let p = e.path();
            let Ok(meta) = std::fs::symlink_metadata(&p) else {
                continue;
            };
            if meta.file_type().is_symlink() {
                continue;
            }
            if meta.is_dir() {
                walk(base, &p, out);
            } else {
                let bytes = std::fs::read(&p).unwrap_or_default();
                let rel = p.strip_prefix(base).unwrap().to_path_buf();
                out.insert(rel, (meta.len(), fnv64(&bytes), meta.modified().ok()));
            }
        }
    }
    let mut out = BTreeMap::new();
    walk(dir, dir, &mut out);
    out
}

/// Run the binary with `args` in `dir`: (status, stdout, stderr).
fn run(dir: &Path, args: &[String]) -> (Option<i32>, Vec<u8>, Vec<u8>) {
    let mut child = Command::new(env!("CARGO_BIN_EXE_dexter"))
        .args(args)
        .current_dir(dir)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("the dexter binary starts");
    let drain = |mut r: Box<dyn Read + Send>| {
        std::thread::spawn(move || {
            let mut v = Vec::new();
            let _ = r.read_to_end(&mut v);
            v
        })
    };
    let out = drain(Box::new(child.stdout.take().unwrap()));
    let err = drain(Box::new(child.stderr.take().unwrap()));
    let start = Instant::now();
    let status = loop {
        if let Some(s) = child.try_wait().expect("wait") {
            break s;
        }
        if start.elapsed() > COMMAND_TIMEOUT {
            let _ = child.kill();
            panic!(
                "`dexter {}` ran longer than {COMMAND_TIMEOUT:?}",
                args.join(" ")
            );
        }
        std::thread::sleep(Duration::from_millis(5));
    };
    (status.code(), out.join().unwrap(), err.join().unwrap())
}

/// The case file of one command's run in `dir`.
fn run_case(case: &Case, dir: &Path) -> String {
    let before = snapshot(dir);
    let (status, stdout, stderr) = run(dir, &case.args);
    let after = snapshot(dir);
    let mut s = format!(
        "# {} (from {})\nargs: {:?}\nstatus: {}\n",
        case.line,
        case.doc,
        case.args,
        status.map_or("killed by a signal".into(), |c| c.to_string())
    );
    s += &shown("stdout", &stdout, dir);
    s += &shown("stderr", &stderr, dir);
    s += "--- files written (path, bytes, fnv64)\n";
    for (path, stamp) in &after {
        if before.get(path) != Some(stamp) {
            s += &format!("{} {} {:016x}\n", path.display(), stamp.0, stamp.1);
        }
    }
    s
}

/// Run `cases` in a fresh scratch directory and compare (or bless) them against
/// `tests/documented/<group>`.
fn check(group: &str, cases: &[Case]) {
    let expected_dir = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests")
        .join("documented")
        .join(group);
    let scratch = Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join("documented-commands")
        .join(if group.is_empty() { "main" } else { group });
    let work = scratch.join("work");
    let actual_dir = scratch.join("actual");
    let _ = std::fs::remove_dir_all(&scratch);
    std::fs::create_dir_all(&work).unwrap();
    std::os::unix::fs::symlink(workspace().join("scenes"), work.join("scenes")).unwrap();
    let bless = std::env::var_os("DEXTER_BLESS").is_some_and(|v| v == "1");
    let mut failures = Vec::new();
    let mut names = Vec::new();
    for case in cases {
        let name = format!("{}.txt", case.slug());
        let actual = run_case(case, &work);
        let path = expected_dir.join(&name);
        names.push(name.clone());
        if bless {
            std::fs::create_dir_all(&expected_dir).unwrap();
            std::fs::write(&path, &actual).unwrap();
            continue;
        }
        let expected = std::fs::read_to_string(&path).unwrap_or_default();
        if expected != actual {
            std::fs::create_dir_all(&actual_dir).unwrap();
            std::fs::write(actual_dir.join(&name), &actual).unwrap();
            failures.push(format!(
                "`{}` ({}): differs from {} (actual in {})\n{}",
                case.line,
                case.doc,
                path.display(),
                actual_dir.join(&name).display(),
                first_difference(&expected, &actual)
            ));
        }
    }
    if bless {
        // drop case files of commands the docs no longer hold
        for e in std::fs::read_dir(&expected_dir)
            .into_iter()
            .flatten()
            .flatten()
        {
            let n = e.file_name().to_string_lossy().to_string();
            if n.ends_with(".txt") && !names.contains(&n) {
                std::fs::remove_file(e.path()).unwrap();
            }
        }
        return;
    }
    assert!(
        failures.is_empty(),
        "{} of {} documented commands changed their output (bless a deliberate change with DEXTER_BLESS=1):\n\n{}",
        failures.len(),
        cases.len(),
        failures.join("\n\n")
    );
}

fn first_difference(expected: &str, actual: &str) -> String {
    if expected.is_empty() {
        return "  no blessed output: run with DEXTER_BLESS=1".into();
    }
    let (e, a): (Vec<&str>, Vec<&str>) = (expected.lines().collect(), actual.lines().collect());
    let i = (0..e.len().max(a.len()))
        .find(|&i| e.get(i) != a.get(i))
        .unwrap_or(0);
    format!(
        "  line {}:\n  expected: {}\n  actual:   {}",
        i + 1,
        e.get(i).unwrap_or(&"<end>"),
        a.get(i).unwrap_or(&"<end>")
    )
}

#[test]
fn documented_commands_give_the_blessed_output() {
    let cases: Vec<Case> = documented_commands()
        .into_iter()
        .filter(|c| !c.hil())
        .collect();
    assert!(cases.len() >= 10, "found only {} commands", cases.len());
    check("", &cases);
}

/// The `--hil` lines: the firmware is built first (as `scripts/test.sh` does), then each
/// line runs unchanged; it fails, naming what to install, without QEMU or the target.
#[test]
fn documented_hil_commands_give_the_blessed_output() {
    let cases: Vec<Case> = documented_commands()
        .into_iter()
        .filter(Case::hil)
        .collect();
    assert!(!cases.is_empty(), "the docs show a --hil command");
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    let build = Command::new(cargo)
        .current_dir(workspace())
        .args([
            "build",
            "-p",
            "dexter-mps2-an386",
            "--release",
            "--target",
            "thumbv7em-none-eabihf",
        ])
        .output()
        .expect("cargo runs");
    assert!(
        build.status.success(),
        "building the firmware failed (install the target with `rustup target add thumbv7em-none-eabihf`):\n{}",
        String::from_utf8_lossy(&build.stderr)
    );
    check("hil", &cases);
}

#[test]
fn extraction_joins_continuations_and_drops_comments() {
    let doc = "text `dexter run x.toml` inline is not a command\n\
```sh\n\
cargo run --release        # the main job\n\
cargo run --release -- run a.toml --json\n\
$ dexter sweep b.toml --range k=1:2:3 \\\n    --csv out.csv\n\
cargo install cargo-fuzz\n\
```\n\
dexter run outside.toml\n";
    let cases = extract("x.md", doc);
    let args: Vec<Vec<String>> = cases.iter().map(|c| c.args.clone()).collect();
    let v = |s: &str| -> Vec<String> { s.split_whitespace().map(str::to_string).collect() };
    assert_eq!(
        args,
        vec![
            v(""),
            v("run a.toml --json"),
            v("sweep b.toml --range k=1:2:3 --csv out.csv")
        ]
    );
    assert_eq!(
        cases[2].line,
        "$ dexter sweep b.toml --range k=1:2:3 --csv out.csv"
    );
}

#[test]
fn masking_hides_timings_only() {
    let text =
        "wall time        0.007579 s\n  time: simulated 92.554 s, wall 0.197 ms (2031 gap)\n\
{\"wall_time_s\":1.5e-4,\"x\":2}\n  \"wall_time_s\": 0.25,\n\
HIL 0 mismatches, steps/s 14000, instr min/mean/max 200/250.5/291\n  wall time 1.234 ms\n";
    assert_eq!(
        mask(text),
        "wall time        <T> s\n  time: simulated 92.554 s, wall <T> ms (2031 gap)\n\
{\"wall_time_s\":<T>,\"x\":2}\n  \"wall_time_s\": <T>,\n\
HIL 0 mismatches, steps/s <T>, instr min/mean/max <T>\n  wall time <T> ms\n"
    );
    assert_eq!(
        mask("\"step_instructions_max\": 291,"),
        "\"step_instructions_max\": <T>,"
    );
}
