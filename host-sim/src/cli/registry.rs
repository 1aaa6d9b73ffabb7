//! The registry: every system, as a plain table of entries in the order they are asked to
//! claim a scene ([`SYSTEMS`]), and the verbs each runs. Adding a system is one line here.

use crate::scene::SceneFile;
use crate::system::basin::Basins;
use crate::system::{unsupported, Analyzes, Failure, Sweeps, System};
use crate::systems::{arm, feeder, hopper, line, planar, planar_juggler, spatial_juggler};
use crate::verbs::basin::BasinRequest;
use crate::verbs::merge::{MergeRequest, ShardSet};
use crate::verbs::{self, AnalyzeRequest, RunRequest, SweepRequest};

/// One verb of one system on a scene.
pub type Verb<R> = fn(&SceneFile, &R) -> Result<(), Failure>;

/// `dexter merge` of one system's shards.
pub type Merge = fn(ShardSet, &MergeRequest) -> Result<(), Failure>;

/// One system as the CLI dispatches on it.
#[derive(Clone, Copy)]
pub struct Entry {
    /// [`System::NAME`].
    pub name: &'static str,
    /// [`System::claims`].
    pub claims: fn(&toml::Table) -> bool,
    /// `dexter run`.
    pub run: Verb<RunRequest>,
    /// `dexter sweep` (refused for a system that does not sweep).
    pub sweep: Verb<SweepRequest>,
    /// `dexter analyze` (refused for a system without an analysis).
    pub analyze: Verb<AnalyzeRequest>,
    /// `dexter basin` (refused for a system that does not classify its runs).
    pub basin: Verb<BasinRequest>,
    /// `dexter merge` of a sweep's shards.
    pub merge_sweep: Merge,
    /// `dexter merge` of a basin map's shards.
    pub merge_basin: Merge,
}

impl Entry {
    /// System `S`: it runs; `sweep` and `analyze` are refused (exit 2).
    pub const fn of<S: System>() -> Self {
        Self {
            name: S::NAME,
            claims: S::claims,
            run: verbs::run::<S>,
            sweep: no_sweep::<S>,
            analyze: no_analysis::<S>,
            basin: no_basin::<S>,
            merge_sweep: no_merge::<S>,
            merge_basin: no_merge::<S>,
        }
    }

    /// The same entry, sweeping ([`Sweeps`]).
    pub const fn sweeps<S: Sweeps>(self) -> Self {
        Self {
            sweep: verbs::sweep::<S>,
            merge_sweep: verbs::merge::merge_sweep::<S>,
            ..self
        }
    }

    /// The same entry, analyzing ([`Analyzes`]).
    pub const fn analyzes<S: Analyzes>(self) -> Self {
        Self {
            analyze: verbs::analyze::<S>,
            ..self
        }
    }

    /// The same entry, drawing basin maps ([`Basins`]).
    pub const fn basins<S: Basins>(self) -> Self {
        Self {
            basin: verbs::basin::basin::<S>,
            merge_basin: verbs::basin::merge::<S>,
            ..self
        }
    }
}

/// `basin` refused for system `S` (exit 2).
fn no_basin<S: System>(_: &SceneFile, _: &BasinRequest) -> Result<(), Failure> {
    Err(unsupported::<S>("basin"))
}

/// `merge` refused for system `S` (exit 2): it neither sweeps nor maps basins.
fn no_merge<S: System>(_: ShardSet, _: &MergeRequest) -> Result<(), Failure> {
    Err(unsupported::<S>("merge"))
}

/// `sweep` refused for system `S` (exit 2).
fn no_sweep<S: System>(_: &SceneFile, _: &SweepRequest) -> Result<(), Failure> {
    Err(unsupported::<S>("sweep"))
}

/// `analyze` refused for system `S` (exit 2).
fn no_analysis<S: System>(_: &SceneFile, _: &AnalyzeRequest) -> Result<(), Failure> {
    Err(unsupported::<S>("analyze"))
}

/// Every system, in the order they are asked to claim a scene: the line system last (it
/// claims every scene, so it runs those no other system claims).
pub static SYSTEMS: [Entry; 8] = [
    Entry::of::<arm::ArmSystem>(),
    Entry::of::<hopper::sampled::SampledHopperSystem>(),
    Entry::of::<feeder::FeederSystem>().sweeps::<feeder::FeederSystem>(),
    Entry::of::<hopper::HopperSystem>()
        .sweeps::<hopper::HopperSystem>()
        .analyzes::<hopper::HopperSystem>(),
    Entry::of::<planar_juggler::PlanarJugglerSystem>(),
    Entry::of::<spatial_juggler::SpatialJugglerSystem>()
        .analyzes::<spatial_juggler::SpatialJugglerSystem>(),
    Entry::of::<planar::PlanarSystem>()
        .sweeps::<planar::PlanarSystem>()
        .analyzes::<planar::PlanarSystem>(),
    Entry::of::<line::LineSystem>()
        .sweeps::<line::LineSystem>()
        .analyzes::<line::LineSystem>()
        .basins::<line::LineSystem>(),
];

/// The system that runs a scene with these top-level tables.
pub fn claim(table: &toml::Table) -> &'static Entry {
    SYSTEMS
        .iter()
        .find(|s| (s.claims)(table))
        .unwrap_or(&SYSTEMS[SYSTEMS.len() - 1])
}
