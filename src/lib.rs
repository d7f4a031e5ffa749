//! hyrt: a hybrid CPU renderer.
pub mod scene;
