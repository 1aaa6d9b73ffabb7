//! The command line: the registry the CLI dispatches on ([`registry`]).

pub mod registry;
