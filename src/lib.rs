//! hyrt: a hybrid CPU renderer.
//!
//! The library behind the `hyrt` CLI: scene model and loaders ([`scene`]), the effect
//! planner ([`plan`]), the one pipeline with per-stage strategies ([`render`]), film output
//! ([`film`]), image metrics ([`metrics`]), and measurement ([`measure`]) with sweeps over the
//! knobs ([`sweep`], plotted by [`plot`]).

pub mod bench;
pub mod camera;
pub mod cli;
pub mod film;
pub mod measure;
pub mod metrics;
pub mod options;
pub mod orbit;
pub mod output;
pub mod plan;
pub mod plot;
pub mod render;
pub mod scene;
pub mod stats;
pub mod sweep;
