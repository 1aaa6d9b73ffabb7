//! Shards of a sweep or a basin map (`--shard K/N`) and the files they write, which
//! `dexter merge` reads back.
//!
//! **Which points.** The points are dealt to the `N` shards by their estimated cost
//! ([`partition`]): the greedy longest-processing-time rule, most costly point first, each
//! to the shard with the least cost so far (ties: the lower index). Equal costs deal the
//! points round-robin (point `i` to shard `i mod N + 1`), so neighbouring points, whose
//! runs tend to be alike, are spread over every shard; where the system knows that runs
//! differ in length (a swept run length such as `stop.impacts`), the cost follows it and
//! no shard's cost exceeds another's by more than one point's. The rule depends only on
//! the grid and `N`: every shard, and the merge, computes the same deal.
//!
//! **The file.** A shard's CSV is whole on its own:
//!
//! ```text
//! # dexter sweep shard 2/4 of line-juggler: 50 of 200 points
//! # sweep hash 8d868b8b92fb8675 (CRC-64/XZ of the sweep line below: scene, --set, ranges, --keep)
//! # sweep {"verb":"sweep","scene":"line-juggler","table":"[actuator]\n...","range":{...},...}
//! point,control.kappa1_s2pm2,period,end,apex_height_m
//! 1,2.0351758793969849e-2,1,impacts,7.8507425482080173e-1
//! ...
//! # end of shard 2/4: 50 points, rows CRC-64/XZ 682f99007f97d3b3
//! ```
//!
//! The `point` column is the point's index in the whole grid; the rest of each row is the
//! row the unsharded command writes. The `sweep` line holds everything the merge needs to
//! rebuild the sweep (the scene table with `--set` applied, the ranges, `--keep`), so the
//! merge needs no scene file; its hash names the sweep. The last line says the shard is
//! complete and what its rows' checksum is (the file is also written whole or not at all,
//! [`crate::output`]).

use crate::grid::Range;
use crate::output::{AtomicFile, OutputError};
use serde::{Deserialize, Serialize};
use std::cmp::Reverse;
use std::collections::BinaryHeap;
use std::io::{BufRead, BufReader, Write};
use std::path::{Path, PathBuf};

/// The `K`-th of `N` shards (`1 <= K <= N`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Shard {
    /// Which shard, from 1.
    pub k: u32,
    /// How many.
    pub n: u32,
}

impl std::fmt::Display for Shard {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}/{}", self.k, self.n)
    }
}

impl Shard {
    /// Parse `K/N` for a grid of `points` points; the message names `--shard`.
    pub fn parse(text: &str, points: usize) -> Result<Self, String> {
        let bad = |why: &str| format!("--shard `{text}`: {why}");
        let (k, n) = text
            .split_once('/')
            .ok_or_else(|| bad("expected K/N, the K-th of N shards (e.g. --shard 2/4)"))?;
        let int = |s: &str, what: &str| {
            s.trim()
                .parse::<u32>()
                .map_err(|_| bad(&format!("{what} `{s}` is not a whole number")))
        };
        let (k, n) = (int(k, "K")?, int(n, "N")?);
        if n == 0 {
            return Err(bad("N must be at least 1"));
        }
        if k == 0 || k > n {
            return Err(bad(&format!("K must be in 1..={n} (shards count from 1)")));
        }
        if n as usize > points {
            return Err(bad(&format!(
                "the grid has {points} points, so at most {points} shards"
            )));
        }
        Ok(Self { k, n })
    }
}

/// The shard (0-based) of each point whose estimated cost is `costs[i]`: the greedy
/// longest-processing-time deal (module docs). A cost that is not a positive finite
/// number counts as 1.
pub fn partition(costs: &[f64], n: u32) -> Vec<u32> {
    let cost = |i: usize| match costs[i] {
        c if c.is_finite() && c > 0.0 => c,
        _ => 1.0,
    };
    let mut order: Vec<usize> = (0..costs.len()).collect();
    // most costly first; equal costs in index order (the sort is stable)
    order.sort_by(|&a, &b| cost(b).total_cmp(&cost(a)));
    // positive finite loads order as their bit patterns do
    let mut loads: BinaryHeap<Reverse<(u64, u32)>> = (0..n).map(|s| Reverse((0, s))).collect();
    let mut owner = vec![0; costs.len()];
    for i in order {
        let Some(Reverse((load, s))) = loads.pop() else {
            break;
        };
        owner[i] = s;
        loads.push(Reverse(((f64::from_bits(load) + cost(i)).to_bits(), s)));
    }
    owner
}

/// The points of `shard`, in order, given [`partition`]'s owners.
pub fn points_of(owner: &[u32], shard: Shard) -> Vec<usize> {
    (0..owner.len())
        .filter(|&i| owner[i] == shard.k - 1)
        .collect()
}

/// What a sweep is: everything that decides its points and rows. Hashed, and written on
/// every shard's `sweep` line.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SweepId {
    /// The command: `sweep` or `basin`.
    pub verb: String,
    /// The scene's name (its file stem).
    pub scene: String,
    /// The scene table with `--set` applied (written as TOML text in a JSON string, so
    /// that its numbers keep their TOML types).
    #[serde(with = "toml_text")]
    pub table: toml::Table,
    /// `--range`.
    pub range: Range,
    /// `--range2`.
    pub range2: Option<Range>,
    /// `--keep` (as given; ignored by systems that keep nothing).
    pub keep: usize,
}

impl SweepId {
    /// The `sweep` line's JSON.
    pub fn json(&self) -> Result<String, String> {
        serde_json::to_string(self).map_err(|e| format!("cannot describe the sweep: {e}"))
    }
}

/// A TOML table as its TOML text.
mod toml_text {
    use serde::{de::Error as _, ser::Error as _, Deserialize, Deserializer, Serializer};

    pub fn serialize<S: Serializer>(t: &toml::Table, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(&toml::to_string(t).map_err(S::Error::custom)?)
    }

    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<toml::Table, D::Error> {
        String::deserialize(d)?.parse().map_err(D::Error::custom)
    }
}

/// CRC-64/XZ: the sweep's hash and the rows' checksum.
const CRC: crc::Crc<u64> = crc::Crc::<u64>::new(&crc::CRC_64_XZ);

/// The hash that names a sweep: CRC-64/XZ of its `sweep` line's JSON, 16 hex digits.
pub fn hash(json: &str) -> String {
    format!("{:016x}", CRC.checksum(json.as_bytes()))
}

const SWEEP_LINE: &str = "# sweep ";
const HASH_LINE: &str = "# sweep hash ";

/// The trailer that ends a complete shard: its points and the CRC-64/XZ of its rows (the
/// lines between the CSV header and the trailer, newlines included).
fn trailer(shard: Shard, points: usize, rows: u64) -> String {
    format!("# end of shard {shard}: {points} points, rows CRC-64/XZ {rows:016x}")
}

/// A shard's CSV being written: header, one prefixed row per CSV row, trailer; committed
/// whole ([`AtomicFile`]).
pub struct ShardWriter {
    file: AtomicFile,
    shard: Shard,
    points: usize,
    rows: crc::Digest<'static, u64>,
}

impl ShardWriter {
    /// Start `path` with the header of `shard` of the sweep `id` (`json`, its
    /// [`SweepId::json`]), holding `points` of `total` points, with the CSV `columns`
    /// (the unsharded header).
    pub fn create(
        path: &Path,
        id: &SweepId,
        json: &str,
        shard: Shard,
        (points, total): (usize, usize),
        columns: &str,
    ) -> Result<Self, OutputError> {
        let mut file = AtomicFile::create(path)?;
        let w = file.writer();
        let head = writeln!(
            w,
            "# dexter {} shard {shard} of {}: {points} of {total} points",
            id.verb, id.scene
        )
        .and_then(|_| {
            writeln!(
                w,
                "{HASH_LINE}{} (CRC-64/XZ of the sweep line below: scene, --set, ranges, --keep)",
                hash(json)
            )
        })
        .and_then(|_| writeln!(w, "{SWEEP_LINE}{json}"))
        .and_then(|_| writeln!(w, "point,{columns}"));
        head.map_err(|e| file.error(e))?;
        Ok(Self {
            file,
            shard,
            points,
            rows: CRC.digest(),
        })
    }

    /// Append point `i`'s rows (`rows`: the unsharded command's lines, each ending in a
    /// newline), each prefixed with `i`.
    pub fn push(&mut self, i: usize, rows: &[u8]) -> Result<(), OutputError> {
        let w = self.file.writer();
        let digest = &mut self.rows;
        let r = rows.split_inclusive(|&b| b == b'\n').try_for_each(|line| {
            let index = format!("{i},");
            digest.update(index.as_bytes());
            digest.update(line);
            w.write_all(index.as_bytes())
                .and_then(|_| w.write_all(line))
        });
        r.map_err(|e| self.file.error(e))
    }

    /// Write the trailer and commit.
    pub fn commit(mut self) -> Result<(), OutputError> {
        let end = trailer(self.shard, self.points, self.rows.finalize());
        writeln!(self.file.writer(), "{end}").map_err(|e| self.file.error(e))?;
        self.file.commit()
    }
}

/// A shard's CSV being read: its header, then its rows point by point.
pub struct ShardFile {
    /// Where it is.
    pub path: PathBuf,
    /// Which shard it says it is.
    pub shard: Shard,
    /// The sweep hash on its header.
    pub hash: String,
    /// Its `sweep` line's JSON.
    pub json: String,
    /// Its CSV header, without the `point,` column.
    pub columns: String,
    lines: std::io::Lines<BufReader<std::fs::File>>,
    /// The next line not yet consumed.
    next: Option<String>,
    points: usize,
    rows: crc::Digest<'static, u64>,
}

impl ShardFile {
    /// Open `path` and read its header; an error says why it is not a shard.
    pub fn open(path: &Path) -> Result<Self, String> {
        let name = path.display();
        let f = std::fs::File::open(path).map_err(|e| format!("cannot read {name}: {e}"))?;
        let mut lines = BufReader::new(f).lines();
        let mut line = |what: &str| match lines.next() {
            Some(Ok(l)) => Ok(l),
            Some(Err(e)) => Err(format!("cannot read {name}: {e}")),
            None => Err(format!(
                "{name} is not a dexter shard: it ends before its {what}"
            )),
        };
        let first = line("first line")?;
        let shard = shard_of_title(&first)
            .ok_or_else(|| format!("{name} is not a dexter shard (its first line is not `# dexter sweep shard K/N ...`)"))?;
        let hash_line = line("sweep hash")?;
        let hash = hash_line
            .strip_prefix(HASH_LINE)
            .and_then(|h| h.split_whitespace().next())
            .ok_or_else(|| format!("{name}: its second line is not the sweep hash"))?
            .to_string();
        let json = line("sweep line")?
            .strip_prefix(SWEEP_LINE)
            .ok_or_else(|| format!("{name}: its third line is not the sweep line"))?
            .to_string();
        if self::hash(&json) != hash {
            return Err(format!(
                "{name}: its sweep line does not hash to its sweep hash {hash} (the file was changed)"
            ));
        }
        let columns = line("CSV header")?
            .strip_prefix("point,")
            .ok_or_else(|| format!("{name}: its CSV header does not start with `point,`"))?
            .to_string();
        let next = lines
            .next()
            .transpose()
            .map_err(|e| format!("cannot read {name}: {e}"))?;
        Ok(Self {
            path: path.to_path_buf(),
            shard,
            hash,
            json,
            columns,
            lines,
            next,
            points: 0,
            rows: CRC.digest(),
        })
    }

    /// The sweep its header describes.
    pub fn id(&self) -> Result<SweepId, String> {
        serde_json::from_str(&self.json).map_err(|e| {
            format!(
                "{}: its sweep line cannot be read: {e}",
                self.path.display()
            )
        })
    }

    /// The rows of point `i` (the shard's next point), without the `point` column; a point
    /// may have none.
    pub fn next_point(&mut self, i: usize) -> Result<Vec<String>, String> {
        let mut rows = Vec::new();
        while let Some(line) = self.next.take() {
            if line.starts_with('#') {
                self.next = Some(line);
                break;
            }
            let (index, row) = line.split_once(',').unwrap_or((line.as_str(), ""));
            match index.parse::<usize>() {
                Ok(j) if j == i => {
                    self.rows.update(line.as_bytes());
                    self.rows.update(b"\n");
                    rows.push(row.to_string())
                }
                Ok(j) if j > i => {
                    self.next = Some(line);
                    break;
                }
                _ => {
                    return Err(format!(
                        "{} (shard {}): a row of point `{index}` where point {i}'s rows were expected (rows out of order, or not of this shard)",
                        self.path.display(),
                        self.shard
                    ))
                }
            }
            self.next = self
                .lines
                .next()
                .transpose()
                .map_err(|e| format!("cannot read {}: {e}", self.path.display()))?;
        }
        self.points += 1;
        Ok(rows)
    }

    /// Check that every row was read, and the file ends with its trailer, whose checksum
    /// its rows have.
    pub fn finish(mut self) -> Result<(), String> {
        let name = self.path.display().to_string();
        let end = trailer(self.shard, self.points, self.rows.finalize());
        let count = format!("# end of shard {}: {} points,", self.shard, self.points);
        match self.next.take() {
            Some(l) if l == end => {}
            Some(l) if l.starts_with(&count) => {
                return Err(format!(
                    "{name} (shard {}): its rows do not match their checksum (`{l}`; they were changed)",
                    self.shard
                ))
            }
            Some(l) if l.starts_with('#') => {
                return Err(format!(
                "{name} (shard {}): ends `{l}`, expected `{end}` (a different number of points)",
                self.shard
            ))
            }
            Some(l) => {
                return Err(format!(
                    "{name} (shard {}): a row not of this shard's points: `{l}`",
                    self.shard
                ))
            }
            None => {
                return Err(format!(
                    "{name} (shard {}) is incomplete: it lacks its last line `{end}`",
                    self.shard
                ))
            }
        }
        match self.lines.next() {
            None => Ok(()),
            Some(_) => Err(format!(
                "{name} (shard {}): lines after `{end}`",
                self.shard
            )),
        }
    }
}

/// The shard `K/N` named by a first line `# dexter VERB shard K/N of ...`.
fn shard_of_title(line: &str) -> Option<Shard> {
    let rest = line.strip_prefix("# dexter ")?;
    let (_, rest) = rest.split_once(" shard ")?;
    let (kn, _) = rest.split_once(' ')?;
    let (k, n) = kn.split_once('/')?;
    let (k, n) = (k.parse().ok()?, n.parse().ok()?);
    (1..=n).contains(&k).then_some(Shard { k, n })
}

/// Why `path` is not already the complete `shard` of the sweep `json` with `points` and
/// CSV `columns`, or `None` if it is (a re-run then has nothing to do).
pub fn incomplete(
    path: &Path,
    json: &str,
    shard: Shard,
    points: &[usize],
    columns: &str,
) -> Option<String> {
    let mut f = match ShardFile::open(path) {
        Ok(f) => f,
        Err(e) => return Some(e),
    };
    if f.hash != hash(json) || f.json != json {
        return Some(format!(
            "{} is a shard of another sweep (hash {})",
            path.display(),
            f.hash
        ));
    }
    if f.shard != shard {
        return Some(format!(
            "{} is shard {}, not {shard}",
            path.display(),
            f.shard
        ));
    }
    if f.columns != columns {
        return Some(format!("{} has other columns", path.display()));
    }
    for &i in points {
        if let Err(e) = f.next_point(i) {
            return Some(e);
        }
    }
    f.finish().err()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shard_arguments_are_checked_and_named() {
        assert_eq!(Shard::parse("2/4", 200), Ok(Shard { k: 2, n: 4 }));
        assert_eq!(Shard::parse("1/1", 1), Ok(Shard { k: 1, n: 1 }));
        for bad in [
            "0/4", "5/4", "4", "a/4", "2/b", "2/0", "-1/4", "1/201", "2/4/8",
        ] {
            let e = Shard::parse(bad, 200).unwrap_err();
            assert!(e.starts_with(&format!("--shard `{bad}`")), "{bad}: {e}");
        }
        assert!(Shard::parse("1/201", 200)
            .unwrap_err()
            .contains("at most 200 shards"));
    }

    /// Loads per shard of a deal.
    fn loads(costs: &[f64], owner: &[u32], n: u32) -> Vec<f64> {
        let mut l = vec![0.0; n as usize];
        for (c, &s) in costs.iter().zip(owner) {
            l[s as usize] += c;
        }
        l
    }

    #[test]
    fn equal_costs_are_dealt_round_robin() {
        let owner = partition(&[1.0; 10], 4);
        assert_eq!(owner, [0, 1, 2, 3, 0, 1, 2, 3, 0, 1]);
        assert_eq!(points_of(&owner, Shard { k: 2, n: 4 }), [1, 5, 9]);
    }

    #[test]
    fn unequal_costs_are_balanced_not_just_counted() {
        // every fourth run is ten times as long: round-robin would give shard 1 all of them
        // (cost 50 + 0 against 15); the deal's loads differ by at most one point's cost
        let costs: Vec<f64> = (0..20)
            .map(|i| if i % 4 == 0 { 10.0 } else { 1.0 })
            .collect();
        let l = loads(&costs, &partition(&costs, 4), 4);
        let (lo, hi) = l
            .iter()
            .fold((f64::MAX, 0.0f64), |(a, b), &v| (a.min(v), b.max(v)));
        assert!(hi - lo <= 10.0, "{l:?}");
        assert!(hi <= 65.0 / 4.0 + 10.0, "{l:?}");
        // a run length rising along the grid (a swept stop.impacts): 1..=100
        let costs: Vec<f64> = (1..=100).map(f64::from).collect();
        let l = loads(&costs, &partition(&costs, 4), 4);
        let total: f64 = costs.iter().sum();
        for v in &l {
            assert!((v - total / 4.0).abs() <= 100.0, "{l:?}");
        }
        // every point dealt once; bad costs count as 1
        let owner = partition(&[f64::NAN, -1.0, 0.0, f64::INFINITY], 2);
        assert_eq!(owner, [0, 1, 0, 1]);
    }

    #[test]
    fn a_shard_file_reads_back_point_by_point() {
        let dir = std::env::temp_dir().join(format!("dexter-shard-{}", std::process::id()));
        let path = dir.join("s.csv");
        let id = SweepId {
            verb: "sweep".into(),
            scene: "s".into(),
            table: toml::Table::new(),
            range: Range::parse("a.b=0:1:5").unwrap(),
            range2: None,
            keep: 3,
        };
        let json = id.json().unwrap();
        let shard = Shard { k: 2, n: 2 };
        let mut w = ShardWriter::create(&path, &id, &json, shard, (2, 5), "a.b,v").unwrap();
        w.push(1, b"x,1\nx,2\n").unwrap();
        w.push(3, b"").unwrap();
        w.commit().unwrap();
        let text = std::fs::read_to_string(&path).unwrap();
        assert!(
            text.starts_with("# dexter sweep shard 2/2 of s: 2 of 5 points\n"),
            "{text}"
        );
        let rows = "1,x,1\n1,x,2\n";
        let end = format!(
            "# end of shard 2/2: 2 points, rows CRC-64/XZ {:016x}\n",
            CRC.checksum(rows.as_bytes())
        );
        assert!(
            text.ends_with(&format!("point,a.b,v\n{rows}{end}")),
            "{text}"
        );
        let mut f = ShardFile::open(&path).unwrap();
        assert_eq!((f.shard, f.columns.as_str()), (shard, "a.b,v"));
        assert_eq!(f.id().unwrap(), id);
        assert_eq!(f.next_point(1).unwrap(), ["x,1", "x,2"]);
        assert!(f.next_point(3).unwrap().is_empty());
        f.finish().unwrap();
        assert_eq!(incomplete(&path, &json, shard, &[1, 3], "a.b,v"), None);
        assert!(incomplete(&path, &json, shard, &[1, 2, 3], "a.b,v").is_some());
        assert!(incomplete(&path, &json, Shard { k: 1, n: 2 }, &[1, 3], "a.b,v").is_some());
        // a changed row is caught by the checksum
        std::fs::write(&path, text.replace("1,x,2", "1,x,3")).unwrap();
        let e = incomplete(&path, &json, shard, &[1, 3], "a.b,v").unwrap();
        assert!(e.contains("checksum"), "{e}");
        // a truncated file is not complete
        std::fs::write(&path, &text[..text.len() - 10]).unwrap();
        let e = incomplete(&path, &json, shard, &[1, 3], "a.b,v").unwrap();
        assert!(e.contains("end of shard 2/2"), "{e}");
        let _ = std::fs::remove_dir_all(&dir);
    }
}
