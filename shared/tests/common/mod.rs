//! Helpers the core's test binaries share.
#![allow(dead_code)]

pub mod tilt;
