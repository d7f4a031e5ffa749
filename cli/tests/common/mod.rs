//! Helpers of the binary's tests: those of the library's tests, and running `hyrt`.
#![allow(dead_code)]

use std::path::Path;

#[path = "../../../tests/common/mod.rs"]
mod shared;
pub use shared::*;

/// Runs the `hyrt` binary with arguments in the project root; returns (success, stdout,
/// stderr).
pub fn hyrt(args: &[&str]) -> (bool, String, String) {
    hyrt_in(&root(), args)
}

/// Runs the `hyrt` binary with arguments in `dir`.
pub fn hyrt_in(dir: &Path, args: &[&str]) -> (bool, String, String) {
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_hyrt"))
        .args(args)
        .current_dir(dir)
        .output()
        .expect("run hyrt");
    (
        out.status.success(),
        String::from_utf8_lossy(&out.stdout).into(),
        String::from_utf8_lossy(&out.stderr).into(),
    )
}
