//! `--shard K/N` and `dexter merge` without a cluster: the shards of a line sweep, a planar
//! map and a basin map, run one after another and merged, give the unsharded command's
//! CSV, summary and plot byte for byte (the unsharded run is the independent oracle); the
//! shards cover the grid once; a complete shard is not run again; a killed shard leaves
//! nothing; bad `--shard` values and bad shard sets are refused (exit 2) naming them.
//! `tests/slurm.rs` runs the same through a real SLURM.

use crate::common;

use common::{dexter, ok, scene, scratch};
use std::collections::BTreeSet;
use std::path::Path;

const LINE: &str = "control.kappa1_s2pm2=0.02:0.09:30";

/// The stderr of a run that must exit 2.
fn refused(args: &[&str]) -> String {
    let out = dexter(args);
    let err = String::from_utf8_lossy(&out.stderr).into_owned();
    assert_eq!(out.status.code(), Some(2), "dexter {args:?}: {err}");
    err
}

/// Run `args` with `--shard k/n --csv dir/s{k}.csv` for every k: the shard files.
fn shards(dir: &Path, args: &[&str], n: u32) -> Vec<String> {
    (1..=n)
        .map(|k| {
            let f = dir.join(format!("s{k}.csv")).display().to_string();
            let spec = format!("{k}/{n}");
            let mut a = args.to_vec();
            a.extend(["--shard", &spec, "--csv", &f]);
            ok(&a);
            f
        })
        .collect()
}

/// The point indices of a shard file (its `point` column).
fn indices(path: &str) -> BTreeSet<usize> {
    std::fs::read_to_string(path)
        .unwrap()
        .lines()
        .filter(|l| !l.starts_with('#') && !l.starts_with("point,"))
        .map(|l| l.split(',').next().unwrap().parse().unwrap())
        .collect()
}

fn read(p: &Path) -> Vec<u8> {
    std::fs::read(p).unwrap_or_else(|e| panic!("{}: {e}", p.display()))
}

#[test]
fn bad_shard_values_are_refused_naming_the_option() {
    let d = scratch("shard-values");
    let csv = d.join("s.csv").display().to_string();
    let s = scene("line-juggler");
    for bad in ["0/4", "5/4", "4", "a/4", "2/0", "1/31", "1.5/4", "2/4/8"] {
        let e = refused(&["sweep", &s, "--range", LINE, "--shard", bad, "--csv", &csv]);
        assert!(e.contains(&format!("--shard `{bad}`")), "{bad}: {e}");
    }
    let e = refused(&[
        "sweep", &s, "--range", LINE, "--shard", "1/31", "--csv", &csv,
    ]);
    assert!(e.contains("at most 30 shards"), "{e}");
    let e = refused(&["sweep", &s, "--range", LINE, "--shard", "1/2"]);
    assert!(e.contains("--shard 1/2 needs --csv FILE"), "{e}");
    let plot = d.join("p").display().to_string();
    let e = refused(&[
        "sweep", &s, "--range", LINE, "--shard", "1/2", "--csv", &csv, "--plot", &plot,
    ]);
    assert!(e.contains("--plot with --shard 1/2"), "{e}");
    let e = refused(&[
        "basin",
        &s,
        "--range",
        "ball.height_m=0.1:1:3",
        "--range2",
        "ball.velocity_mps=0:1:2",
        "--shard",
        "3/2",
        "--csv",
        &csv,
    ]);
    assert!(e.contains("--shard `3/2`"), "{e}");
    // a sweep whose CSV does not hold its points (the feeder's: its planner's messages)
    // cannot be sharded
    let e = refused(&[
        "sweep",
        &scene("1joc-l-part"),
        "--range",
        "feeder.arrival.seed=1:3:3",
        "--shard",
        "1/2",
        "--csv",
        &csv,
    ]);
    assert!(
        e.contains("--shard is not available for feeder scenes"),
        "{e}"
    );
    assert!(!Path::new(&csv).exists(), "a refused shard wrote nothing");
}

#[test]
fn a_merged_line_sweep_is_the_unsharded_sweep_and_a_complete_shard_is_not_run_again() {
    let d = scratch("shard-line");
    let s = scene("line-juggler");
    let args = ["sweep", &s, "--range", LINE, "--keep", "8"];
    let full = d.join("full.csv");
    let mut a = args.to_vec();
    let (f, p1) = (
        full.display().to_string(),
        d.join("p1").display().to_string(),
    );
    a.extend(["--csv", &f, "--plot", &p1]);
    ok(&a);
    let files = shards(&d, &args, 3);
    // the shards cover the grid once
    let sets: Vec<BTreeSet<usize>> = files.iter().map(|f| indices(f)).collect();
    let all: BTreeSet<usize> = sets.iter().flatten().copied().collect();
    assert_eq!(all, (0..30).collect());
    assert_eq!(sets.iter().map(BTreeSet::len).sum::<usize>(), 30);
    // in any order
    let merged = d.join("merged.csv").display().to_string();
    let p2 = d.join("p2").display().to_string();
    ok(&[
        "merge", &merged, &files[2], &files[0], &files[1], "--plot", &p2,
    ]);
    assert!(
        read(Path::new(&merged)) == read(&full),
        "merged CSV differs"
    );
    let svg = "line-juggler-bifurcation.svg";
    assert!(
        read(&d.join("p1").join(svg)) == read(&d.join("p2").join(svg)),
        "plot differs"
    );
    // a complete shard is a no-op, an incomplete one is run again
    let before = read(Path::new(&files[1]));
    let mut a = args.to_vec();
    a.extend(["--shard", "2/3", "--csv", &files[1]]);
    let out = ok(&a);
    assert!(String::from_utf8_lossy(&out.stderr).contains("already complete: nothing to do"));
    let text = String::from_utf8(before.clone()).unwrap();
    std::fs::write(&files[1], &text[..text.len() / 2]).unwrap();
    let out = ok(&a);
    assert!(String::from_utf8_lossy(&out.stderr).contains("running shard 2/3 again"));
    assert!(read(Path::new(&files[1])) == before);
}

#[test]
fn merged_planar_and_hopper_sweeps_and_basin_maps_are_the_unsharded_ones() {
    let d = scratch("shard-planar");
    let s = scene("planar-triangle");
    let args = [
        "sweep",
        &s,
        "--range",
        "planar.kappa=0.8:1.6:5",
        "--range2",
        "planar.initial_theta_rad=0.05:0.4:4",
    ];
    let full = d.join("full.csv").display().to_string();
    let mut a = args.to_vec();
    a.extend(["--csv", &full]);
    let summary = ok(&a).stdout;
    let files = shards(&d, &args, 3);
    let merged = d.join("merged.csv").display().to_string();
    let out = ok(&["merge", &merged, &files[0], &files[1], &files[2]]);
    assert!(
        read(Path::new(&merged)) == read(Path::new(&full)),
        "planar CSV differs"
    );
    // the letter grid and count, with the merged CSV's name where the sweep named its own
    let summary = String::from_utf8(summary).unwrap();
    assert_eq!(String::from_utf8(out.stdout).unwrap(), summary);

    let h = scratch("shard-hopper");
    let s = scene("hopper-fig11");
    let args = [
        "sweep",
        &s,
        "--range",
        "hopper.thrust_tau_mps2=60:200:7",
        "--keep",
        "6",
    ];
    let full = h.join("full.csv").display().to_string();
    let mut a = args.to_vec();
    a.extend(["--csv", &full]);
    let summary = String::from_utf8(ok(&a).stdout).unwrap();
    let files = shards(&h, &args, 3);
    let merged = h.join("merged.csv").display().to_string();
    let out = ok(&["merge", &merged, &files[0], &files[1], &files[2]]);
    assert!(
        read(Path::new(&merged)) == read(Path::new(&full)),
        "hopper CSV differs"
    );
    // the summary names the CSV it wrote
    let out = String::from_utf8(out.stdout).unwrap();
    assert_eq!(out.replace(&merged, &full), summary);

    let b = scratch("shard-basin");
    let s = scene("line-juggler-ideal");
    let args = [
        "basin",
        &s,
        "--range",
        "ball.height_m=0.05:1.5:5",
        "--range2",
        "ball.velocity_mps=-3:3:4",
        "--json",
    ];
    let full = b.join("full.csv").display().to_string();
    let mut a = args.to_vec();
    a.extend(["--csv", &full]);
    let summary = ok(&a).stdout;
    let files = shards(&b, &args, 2);
    let merged = b.join("merged.csv").display().to_string();
    let out = ok(&["merge", &merged, &files[1], &files[0], "--json"]);
    assert!(
        read(Path::new(&merged)) == read(Path::new(&full)),
        "basin CSV differs"
    );
    assert_eq!(out.stdout, summary);
}

#[test]
fn a_merge_refuses_missing_duplicated_mismatched_and_changed_shards_naming_them() {
    let d = scratch("shard-refusals");
    let s = scene("line-juggler");
    let args = ["sweep", &s, "--range", LINE];
    let files = shards(&d, &args, 3);
    let out = d.join("out.csv").display().to_string();
    let e = refused(&["merge", &out, &files[0], &files[2]]);
    assert!(e.contains("shard 2/3 of this sweep is missing"), "{e}");
    let e = refused(&["merge", &out, &files[0]]);
    assert!(
        e.contains("shards 2/3, 3/3 of this sweep are missing"),
        "{e}"
    );
    let e = refused(&["merge", &out, &files[0], &files[1], &files[1], &files[2]]);
    assert!(
        e.contains(&format!(
            "shard 2/3 is given twice: {} and {}",
            files[1], files[1]
        )),
        "{e}"
    );
    // a shard of another sweep (one more point)
    let other = d.join("other.csv").display().to_string();
    ok(&[
        "sweep",
        &s,
        "--range",
        "control.kappa1_s2pm2=0.02:0.09:31",
        "--shard",
        "2/3",
        "--csv",
        &other,
    ]);
    let e = refused(&["merge", &out, &files[0], &other, &files[2]]);
    assert!(
        e.contains(&format!("{other} (shard 2/3) is a shard of another sweep")),
        "{e}"
    );
    // an incomplete shard, a changed row, not a shard at all
    let text = std::fs::read_to_string(&files[1]).unwrap();
    let cut = d.join("cut.csv").display().to_string();
    let end = text.rfind("# end").unwrap();
    std::fs::write(&cut, &text[..end]).unwrap();
    let e = refused(&["merge", &out, &files[0], &cut, &files[2]]);
    assert!(
        e.contains(&format!("{cut} (shard 2/3) is incomplete")),
        "{e}"
    );
    let changed = d.join("changed.csv").display().to_string();
    // one mantissa digit of a row's apex: caught by the read-back (17 digits that are not
    // an f64's own) or by the rows' checksum (the unit tests of crate::shard check that)
    let row = text.lines().nth(4).unwrap();
    let at = row.rfind(',').unwrap() + 3;
    let digit = if &row[at..at + 1] == "1" { "2" } else { "1" };
    let new_row = format!("{}{digit}{}", &row[..at], &row[at + 1..]);
    std::fs::write(&changed, text.replacen(row, &new_row, 1)).unwrap();
    let e = refused(&["merge", &out, &files[0], &changed, &files[2]]);
    assert!(e.contains(&format!("{changed} (shard 2/3)")), "{e}");
    assert!(
        e.contains("checksum") || e.contains("do not read back"),
        "{e}"
    );
    let plain = d.join("plain.csv").display().to_string();
    ok(&["sweep", &s, "--range", LINE, "--csv", &plain]);
    let e = refused(&["merge", &out, &plain]);
    assert!(e.contains(&format!("{plain} is not a dexter shard")), "{e}");
    assert!(!Path::new(&out).exists(), "a refused merge wrote nothing");
}

#[test]
fn a_killed_shard_leaves_no_output() {
    let d = scratch("shard-killed");
    let csv = d.join("s.csv");
    let child = std::process::Command::new(env!("CARGO_BIN_EXE_dexter"))
        .args([
            "sweep",
            &scene("line-juggler"),
            "--range",
            "control.kappa1_s2pm2=0.02:0.09:400",
        ])
        .args([
            "--set",
            "stop.impacts=3000",
            "--set",
            "stop.duration_s=6000",
            "--shard",
            "1/2",
        ])
        .arg("--csv")
        .arg(&csv)
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let temp = || {
        std::fs::read_dir(&d)
            .unwrap()
            .flatten()
            .any(|e| e.file_name().to_string_lossy().starts_with(".s.csv."))
    };
    let start = std::time::Instant::now();
    while !temp() {
        assert!(
            start.elapsed().as_secs() < 30,
            "the shard never started its file"
        );
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    // SAFETY: kill(2) on our own child
    unsafe { libc::kill(child.id() as libc::pid_t, libc::SIGTERM) };
    let out = child.wait_with_output().unwrap();
    assert_eq!(
        out.status.code(),
        Some(143),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(!csv.exists() && !temp(), "a killed shard left output");
}
