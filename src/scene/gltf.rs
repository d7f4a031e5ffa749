//! glTF 2.0 / GLB loading via the gltf crate: geometry, node transforms, base colour.
use std::path::Path;

use anyhow::Result;

use super::MeshData;

/// Loads the default scene of a `.gltf` or `.glb` file, flattened to world space.
pub fn load(path: &Path) -> Result<MeshData> {
    anyhow::bail!("{}: glTF loading not implemented yet", path.display())
}
