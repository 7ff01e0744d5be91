//! Loads the images materials refer to, once per file per scene build.
//!
//! A texture or bump image that cannot be read or decoded is an error naming the file and the
//! script line of the material; with `--missing-textures=warn` the material falls back to its
//! `kd` (or its unbent normal) and a warning is printed once per file. Textures named by mesh
//! files (MTL `map_Kd`, glTF images) are always treated the second way.

use crate::budget::{Account, At, Budget};
use crate::desc::MaterialDesc;
use crate::error::{Error, Loc, Result};
use crate::geometry::mesh::MeshMaterial;
use crate::material::Material;
use crate::material::texture::{BumpMap, Texture};
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// Returns the key of the file at `path`: its canonical path, so that one file named by
/// several spellings (`t.png`, `./t.png`) is decoded once.
fn same_file(path: &Path) -> PathBuf {
    std::fs::canonicalize(path).unwrap_or_else(|_| path.to_path_buf())
}

/// Images loaded so far, by canonical path; `None` records a file that failed in warning mode.
pub struct ImageCache {
    textures: HashMap<PathBuf, Option<Arc<Texture>>>,
    bumps: HashMap<PathBuf, Option<Arc<BumpMap>>>,
    warn_missing: bool,
    /// Where decoded images are charged, before they are decoded.
    account: Account,
}

impl ImageCache {
    /// Returns an empty cache; `warn_missing` turns unreadable images into warnings.
    pub fn new(warn_missing: bool) -> ImageCache {
        ImageCache::with_account(warn_missing, Budget::machine_default().account())
    }

    /// Returns an empty cache that charges the images it decodes to `account`.
    pub fn with_account(warn_missing: bool, account: Account) -> ImageCache {
        ImageCache {
            textures: HashMap::new(),
            bumps: HashMap::new(),
            warn_missing,
            account,
        }
    }

    fn load(&self, path: &Path, loc: &Loc) -> Result<Option<Texture>> {
        // A texture a mesh file names must lie in the scene's folders (the script's own names
        // were checked when it ran); never a warning: the file is there, and not the scene's.
        self.account
            .read_scope()
            .check(path)
            .map_err(|e| Error::at(loc, format!("texture {}: {e}", path.display())))?;
        // Over budget is an error even in warning mode: the file is there, the scene too big.
        self.charge(path, loc)?;
        match Texture::load(path, loc) {
            Ok(t) => Ok(Some(t)),
            Err(e) if self.warn_missing => {
                eprintln!("warning: {e}; using the material's kd instead");
                Ok(None)
            }
            Err(e) => Err(e),
        }
    }

    /// Charges the image at `path` by the size its header gives, before it is decoded: the
    /// decoded pixels and the RGB copy kept. An unreadable header is left to [`Texture::load`].
    fn charge(&self, path: &Path, loc: &Loc) -> Result<()> {
        use image::ImageDecoder;
        let decoder = image::ImageReader::open(path)
            .and_then(|r| r.with_guessed_format())
            .ok()
            .and_then(|r| r.into_decoder().ok());
        let Some(decoder) = decoder else {
            return Ok(());
        };
        let (w, h) = decoder.dimensions();
        let rgb = u64::from(w) * u64::from(h) * 3;
        let what = format!("texture {} ({w}x{h} pixels decoded)", path.display());
        let bytes = decoder.total_bytes().saturating_add(rgb);
        self.account.charge(bytes, what, At::Script(loc))
    }

    /// Returns the colour texture at `path`, loading it on first use.
    pub fn texture(&mut self, path: &Path, loc: &Loc) -> Result<Option<Arc<Texture>>> {
        let key = same_file(path);
        if let Some(t) = self.textures.get(&key) {
            return Ok(t.clone());
        }
        let t = self.load(path, loc)?.map(Arc::new);
        self.textures.insert(key, t.clone());
        Ok(t)
    }

    /// Returns the bump map at `path` (normal map, or height map when grey), loading it once.
    pub fn bump(&mut self, path: &Path, loc: &Loc) -> Result<Option<Arc<BumpMap>>> {
        let key = same_file(path);
        if let Some(b) = self.bumps.get(&key) {
            return Ok(b.clone());
        }
        let b = self
            .load(path, loc)?
            .map(|t| Arc::new(BumpMap::from_texture(t)));
        self.bumps.insert(key, b.clone());
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
