//! hyrt: a hybrid CPU renderer.
//!
//! The library behind the `hyrt` CLI: scene model and loaders ([`scene`]), the effect
//! planner ([`plan`]), the one pipeline with per-stage strategies ([`render`]), film output
//! ([`film`]) and image metrics ([`metrics`]).

pub mod bench;
pub mod camera;
pub mod cli;
pub mod film;
pub mod measure;
pub mod metrics;
pub mod plan;
pub mod render;
pub mod scene;
pub mod stats;
