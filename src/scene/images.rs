//! Loads the images materials refer to, once per file (or embedded image) per scene build.
//!
//! A texture or bump image that cannot be read or decoded is an error naming the file and the
//! script line of the material; with `--missing-textures=warn` the material falls back to its
//! `kd` (or its unbent normal) and a warning is printed once per file. Image files named by mesh
//! files (MTL `map_Kd`, glTF image URIs) are always treated the second way: they often did not
//! travel with the mesh. An image embedded in a glTF file (a buffer view, a `data:` URI) is part
//! of that file: one that cannot be decoded is an error naming the file, the material, the
//! texture and the image index.
//!
//! Every image is charged to the scene's account by its header's size before it is decoded
//! ([`crate::material::texture::header_size`]), and the decoder refuses one whose pixels would
//! take more than its limit ([`crate::material::texture`]).

use crate::budget::{Account, At, Budget};
use crate::desc::MaterialDesc;
use crate::error::{Error, Loc, Result};
use crate::geometry::mesh::{ImageSource, MeshMaterial, MeshPbr};
use crate::material::Material;
use crate::material::pbr::MetalRough;
use crate::material::texture::{BumpMap, Texture, header_size};
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// Returns the key of the file at `path`: its canonical path, so that one file named by
/// several spellings (`t.png`, `./t.png`) is decoded once.
fn same_file(path: &Path) -> PathBuf {
    std::fs::canonicalize(path).unwrap_or_else(|_| path.to_path_buf())
}

/// What a decoded image is kept under.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
enum Key {
    /// An image file, by canonical path ([`same_file`]).
    File(PathBuf),
    /// Image `.1` embedded in the mesh file `.0`.
    Embedded(PathBuf, usize),
}

/// Images loaded so far; `None` records a file that failed in warning mode.
pub struct ImageCache {
    textures: HashMap<Key, Option<Arc<Texture>>>,
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
        let Some((w, h, bytes)) = image::ImageReader::open(path).ok().and_then(header_size) else {
            return Ok(());
        };
        let what = format!("texture {} ({w}x{h} pixels decoded)", path.display());
        self.account.charge(bytes, what, At::Script(loc))
    }

    /// Returns the colour texture at `path`, loading it on first use.
    pub fn texture(&mut self, path: &Path, loc: &Loc) -> Result<Option<Arc<Texture>>> {
        let key = Key::File(same_file(path));
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

    /// Returns the material a mesh file defined, its textures loaded (`loc`: the `gr.mesh`
    /// line, or the glTF file rendered as a scene).
    ///
    /// Mesh files often name textures that did not travel with them (an MTL written on another
    /// machine), so an unreadable image file is always a warning here, and the material keeps
    /// its colour; an embedded image that cannot be decoded is an error.
    pub fn mesh_material(&mut self, m: &MeshMaterial, loc: &Loc) -> Result<Material> {
        let texture = match &m.texture {
            Some(p) => self.lenient_texture(p, loc)?,
            None => None,
        };
        let mut material = Material::from_mesh(m, texture);
        if let Some(pbr) = &m.pbr {
            self.add_gltf_textures(&mut material, &m.name, pbr, loc)?;
        }
        Ok(material)
    }

    /// Returns the texture at `path` as [`ImageCache::texture`] does, an unreadable file always
    /// a warning.
    fn lenient_texture(&mut self, path: &Path, loc: &Loc) -> Result<Option<Arc<Texture>>> {
        let strict = std::mem::replace(&mut self.warn_missing, true);
        let t = self.texture(path, loc);
        self.warn_missing = strict;
        t
    }

    /// Adds a glTF material's textures to `material` (named `name` in its file): the base
    /// colour and metallic-roughness textures as per-hit lookups ([`MetalRough`]), the normal
    /// texture as its bump map.
    fn add_gltf_textures(
        &mut self,
        material: &mut Material,
        name: &str,
        pbr: &MeshPbr,
        loc: &Loc,
    ) -> Result<()> {
        let mut image = |source: &Option<ImageSource>, slot: &str| match source {
            Some(source) => self.mesh_image(source, name, slot, loc),
            None => Ok(None),
        };
        let base = image(&pbr.base_colour_texture, "base colour")?;
        let metal_rough = image(&pbr.metallic_roughness_texture, "metallic-roughness")?;
        let normal = image(&pbr.normal_texture, "normal")?;
        if base.is_some() || metal_rough.is_some() {
            material.metal_rough = Some(Arc::new(MetalRough {
                base_colour: pbr.base_colour.into(),
                metallic: pbr.metallic,
                roughness: pbr.roughness,
                base_colour_texture: base,
                metallic_roughness_texture: metal_rough,
            }));
        }
        material.bump = normal.map(|texture| {
            Arc::new(BumpMap::Scaled {
                texture,
                scale: pbr.normal_scale,
            })
        });
        Ok(())
    }

    /// Returns the texture a mesh material's `slot` texture shows: an image file (unreadable: a
    /// warning, `None`), or an embedded image decoded once per file and image.
    fn mesh_image(
        &mut self,
        source: &ImageSource,
        material: &str,
        slot: &str,
        loc: &Loc,
    ) -> Result<Option<Arc<Texture>>> {
        let (file, index, bytes) = match source {
            ImageSource::File(path) => return self.lenient_texture(path, loc),
            ImageSource::Embedded { file, image, bytes } => (file, *image, bytes),
        };
        let key = Key::Embedded(file.clone(), index);
        if let Some(t) = self.textures.get(&key) {
            return Ok(t.clone());
        }
        // The file is named once: a glTF scene's location is the file itself.
        let named = if loc.line == 0 && *loc.file == *file.display().to_string() {
            String::new()
        } else {
            format!("{}: ", file.display())
        };
        let what = format!("{named}material '{material}': {slot} texture, image {index}");
        let reader = image::ImageReader::new(std::io::Cursor::new(&bytes[..]));
        if let Some((w, h, size)) = header_size(reader) {
            let charged = format!("{what} ({w}x{h} pixels decoded)");
            self.account.charge(size, charged, At::Script(loc))?;
        }
        let t = Texture::decode(bytes).map_err(|e| Error::at(loc, format!("{what}: {e}")))?;
        let t = Some(Arc::new(t));
        self.textures.insert(key, t.clone());
        Ok(t)
    }
}
