//! hyrt: a hybrid CPU renderer.
//!
//! The library behind the `hyrt` command line (`cli/`) and the inspector (`inspect/`): scene
//! model and loaders ([`scene`]), every strategy and knob ([`options`]), the effect planner
//! ([`plan`]), the one pipeline with per-stage strategies ([`render`]), film output ([`film`],
//! [`output`]) and image metrics ([`metrics`]).

pub mod camera;
pub mod film;
pub mod metrics;
pub mod options;
pub mod output;
pub mod plan;
pub mod process;
pub mod render;
pub mod scene;
