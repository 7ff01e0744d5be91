//! Loads the images materials refer to, once per file per scene build.
//!
//! A texture or bump image that cannot be read or decoded is an error naming the file and the
//! script line of the material; with `--missing-textures=warn` the material falls back to its
//! `kd` (or its unbent normal) and a warning is printed once per file. Textures named by mesh
//! files (MTL `map_Kd`, glTF images) are always treated the second way.

use crate::desc::MaterialDesc;
use crate::error::{Loc, Result};
use crate::geometry::mesh::MeshMaterial;
use crate::material::Material;
use crate::material::texture::{BumpMap, Texture};
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// Images loaded so far, by path; `None` records a file that failed in warning mode.
pub struct ImageCache {
    textures: HashMap<PathBuf, Option<Arc<Texture>>>,
    bumps: HashMap<PathBuf, Option<Arc<BumpMap>>>,
    warn_missing: bool,
}

impl ImageCache {
    /// Returns an empty cache; `warn_missing` turns unreadable images into warnings.
    pub fn new(warn_missing: bool) -> ImageCache {
        ImageCache {
            textures: HashMap::new(),
            bumps: HashMap::new(),
            warn_missing,
        }
    }

    fn load(&self, path: &Path, loc: &Loc) -> Result<Option<Texture>> {
        match Texture::load(path, loc) {
            Ok(t) => Ok(Some(t)),
            Err(e) if self.warn_missing => {
                eprintln!("warning: {e}; using the material's kd instead");
                Ok(None)
            }
            Err(e) => Err(e),
        }
    }

    /// Returns the colour texture at `path`, loading it on first use.
    pub fn texture(&mut self, path: &Path, loc: &Loc) -> Result<Option<Arc<Texture>>> {
        if let Some(t) = self.textures.get(path) {
            return Ok(t.clone());
        }
        let t = self.load(path, loc)?.map(Arc::new);
        self.textures.insert(path.to_path_buf(), t.clone());
        Ok(t)
    }

    /// Returns the bump map at `path` (normal map, or height map when grey), loading it once.
    pub fn bump(&mut self, path: &Path, loc: &Loc) -> Result<Option<Arc<BumpMap>>> {
        if let Some(b) = self.bumps.get(path) {
            return Ok(b.clone());
        }
        let b = self
            .load(path, loc)?
            .map(|t| Arc::new(BumpMap::from_texture(t)));
        self.bumps.insert(path.to_path_buf(), b.clone());
        Ok(b)
    }

    /// Returns the material a script described, its images loaded.
    pub fn material(&mut self, d: &MaterialDesc) -> Result<Material> {
        let texture = match &d.texture {
            Some(p) => self.texture(p, &d.loc)?,
            None => None,
        };
        let bump = match &d.bump {
            Some(p) => self.bump(p, &d.loc)?,
            None => None,
        };
        Ok(Material::from_desc(d, texture, bump))
    }

    /// Returns the material a mesh file defined, its texture loaded (`loc`: the `gr.mesh` line).
    ///
    /// Mesh files often name textures that did not travel with them (an MTL written on another
    /// machine), so an unreadable one is always a warning here, and the material keeps its colour.
    pub fn mesh_material(&mut self, m: &MeshMaterial, loc: &Loc) -> Result<Material> {
        let texture = match &m.texture {
            Some(p) => {
                let strict = std::mem::replace(&mut self.warn_missing, true);
                let t = self.texture(p, loc);
                self.warn_missing = strict;
                t?
            }
            None => None,
        };
        Ok(Material::from_mesh(m, texture))
    }
}
