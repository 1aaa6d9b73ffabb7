//! The goal edge (sec. 3.2) and the candidate edge sequences (sec. 3.3).

use super::super::part::Part;
use super::super::primitives::edges_between;
use std::f64::consts::PI;

/// Tolerance on "exactly 180 degrees" between stable edges, rad.
pub const PARALLEL_TOL_RAD: f64 = 1e-6;

/// How the part gets from one stable edge to the next in a sequence.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Hop {
    /// An ordinary turn (Psi < 180 deg).
    Turn,
    /// A convergent turn through the unstable hull edge `via` (Psi = 180 deg).
    Convergent {
        /// The unstable edge the catch lands on.
        via: usize,
    },
}

/// A candidate plan skeleton: stable edges visited, counter-clockwise, and the hops.
#[derive(Clone, Debug, PartialEq)]
pub struct Sequence {
    /// Stable edges from the start edge to the goal edge (the first is the start).
    pub edges: Vec<usize>,
    /// `hops[k]` takes `edges[k]` to `edges[k + 1]`.
    pub hops: Vec<Hop>,
}

/// Counter-clockwise gap from stable edge `s` to the next stable edge (rad, 2 pi when `s`
/// is the only one), and that edge.
pub fn next_stable(part: &Part, s: usize) -> (f64, usize) {
    part.stable_edges()
        .into_iter()
        .filter(|&o| o != s)
        .map(|o| (part.rotation_between(s, o), o))
        .fold((2.0 * PI, s), |a, b| if b.0 < a.0 { b } else { a })
}

/// Whether the part has exactly two stable edges and they are parallel (the class that
/// needs the convergent turn).
pub fn has_parallel_pair(part: &Part) -> bool {
    let st = part.stable_edges();
    st.len() == 2 && (part.rotation_between(st[0], st[1]) - PI).abs() < PARALLEL_TOL_RAD
}

/// The goal edge, as the paper chooses it: a stable edge from which no turn can rotate
/// the part counter-clockwise to the next stable edge (its gap is >= 180 deg); otherwise
/// "any stable edge will serve" and we take the one with the largest gap (ties: lowest
/// index). `None` only for a part without stable edges (impossible for a valid part).
pub fn goal_edge(part: &Part) -> Option<usize> {
    let st = part.stable_edges();
    let gaps: Vec<(f64, usize)> = st.iter().map(|&s| (next_stable(part, s).0, s)).collect();
    if let Some(&(_, s)) = gaps.iter().find(|g| g.0 >= PI - PARALLEL_TOL_RAD) {
        return Some(s);
    }
    gaps.iter()
        .fold(None, |best: Option<(f64, usize)>, &g| match best {
            Some(b) if b.0 >= g.0 - 1e-12 => Some(b),
            _ => Some(g),
        })
        .map(|b| b.1)
}

/// Every counter-clockwise sequence of stable edges from `start` to `goal` rotating the
/// part by at most 360 degrees (every subset of the stable edges in between, in order),
/// with single hops of 180 degrees or more made convergent turns (only possible between
/// parallel stable edges with tipping edges between; dropped when `allow_convergent` is
/// false) or dropped. When `start == goal` the empty sequence comes first, then the full
/// loops. Sorted by number of hops. At most `cap` sequences.
pub fn sequences(
    part: &Part,
    start: usize,
    goal: usize,
    allow_convergent: bool,
    cap: usize,
) -> Vec<Sequence> {
    let mut mids: Vec<(f64, usize)> = part
        .stable_edges()
        .into_iter()
        .filter(|&s| s != start && s != goal)
        .map(|s| (part.rotation_between(start, s), s))
        .collect();
    if start != goal {
        let to_goal = part.rotation_between(start, goal);
        mids.retain(|m| m.0 < to_goal);
    }
    mids.sort_by(|a, b| a.0.total_cmp(&b.0));
    let mut out = Vec::new();
    if start == goal {
        out.push(Sequence {
            edges: vec![start],
            hops: vec![],
        });
    }
    let m = mids.len().min(16);
    let mut masks: Vec<u32> = (0..(1u32 << m)).collect();
    masks.sort_by_key(|k| k.count_ones());
    for mask in masks {
        if out.len() >= cap {
            break;
        }
        let mut edges = vec![start];
        edges.extend((0..m).filter(|i| mask & (1 << i) != 0).map(|i| mids[i].1));
        edges.push(goal);
        if let Some(hops) = hops_for(part, &edges, allow_convergent) {
            out.push(Sequence { edges, hops });
        }
    }
    out
}

fn hops_for(part: &Part, edges: &[usize], allow_convergent: bool) -> Option<Vec<Hop>> {
    edges
        .windows(2)
        .map(|w| {
            let psi = part.rotation_between(w[0], w[1]);
            if psi < PI - PARALLEL_TOL_RAD {
                return Some(Hop::Turn);
            }
            if !allow_convergent || (psi - PI).abs() > PARALLEL_TOL_RAD {
                return None;
            }
            let (between, tips) = edges_between(part, w[0], w[1]);
            (tips && !between.is_empty()).then(|| Hop::Convergent { via: between[0] })
        })
        .collect()
}
