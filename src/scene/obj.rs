//! OBJ + MTL loading via tobj (also gzip-compressed `.obj.gz`).
use std::path::Path;

use anyhow::Result;

use super::MeshData;

/// Loads an OBJ file (or `.obj.gz`) with its MTL materials.
pub fn load(path: &Path) -> Result<MeshData> {
    anyhow::bail!("{}: OBJ loading not implemented yet", path.display())
}
