//! Built-in scenes that need no files.
use super::Scene;

pub const NAMES: &[&str] = &["cornell"];

pub fn by_name(name: &str) -> Option<Scene> {
    match name {
        _ => None,
    }
}
