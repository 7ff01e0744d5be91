//! MTL material libraries for the OBJ loader: reads the files `mtllib` names (through tobj's
//! material-loader closure), maps their materials to [`MeshMaterial`] and gives each triangle
//! the material its `usemtl` named.
//!
//! A library that cannot be opened is skipped, as a missing `.mtl` always was (the faces then
//! carry no material); one that names a device, FIFO or socket (`mtllib /dev/zero`) is an
//! error naming it, never read. A library that opens but is malformed is an error naming the `.mtl` file
//! and line: tobj would panic on a colour with fewer than three numbers, so each line is checked
//! the way tobj reads it before tobj sees the text.
//!
//! `Kd` and `Ks` must lie in `[0, 10]` ([`crate::range::MAX_REFLECTANCE`]); others are an error
//! at their line.
//!
//! Mapping: `Kd` → kd (0.6 grey when absent, the renderer's fallback), `Ks` → ks (0 when
//! absent), `Ns` → shininess, `d` → transparency `1 − d` (else `Tr` → transparency), `Ni` → ior
//! (1 when absent or not positive), `map_Kd` → texture, resolved against the `.mtl` file's folder
//! (options such as `-s 1 1 1` before the file name are dropped).

use super::{ObjError, finite, number};
use crate::geometry::mesh::{MeshData, MeshMaterial};
use glam::Vec3;
use std::cell::RefCell;
use std::path::{Path, PathBuf};

/// Loads the libraries an OBJ file names, remembering the first malformed one.
pub(super) struct MtlLoader<'a> {
    /// The OBJ file's folder, against which `mtllib` names resolve.
    dir: &'a Path,
    /// The folders a library may be read from (`docs/security.md`).
    scope: &'a crate::files::ReadScope,
    /// The first fault found in a library that exists.
    pub fault: RefCell<Option<ObjError>>,
}

impl<'a> MtlLoader<'a> {
    /// Returns a loader resolving library names against `dir`, reading only inside `scope`.
    pub fn new(dir: &'a Path, scope: &'a crate::files::ReadScope) -> MtlLoader<'a> {
        MtlLoader {
            dir,
            scope,
            fault: RefCell::new(None),
        }
    }

    /// Loads one library for tobj; texture names come back resolved to full paths.
    pub fn load(&self, name: &Path) -> tobj::MTLLoadResult {
        let file = self.dir.join(name);
        if file.exists()
            && !file.is_dir()
            && let Err(error) = self
                .scope
                .check(&file)
                .and_then(|()| crate::files::check_regular(&file))
        {
            self.fault
                .borrow_mut()
                .get_or_insert(ObjError::Read { path: file, error });
            return Err(tobj::LoadError::OpenFileFailed);
        }
        let Ok(bytes) = std::fs::read(&file) else {
            return Err(tobj::LoadError::OpenFileFailed);
        };
        // A byte-order mark would hide the first statement (usually `newmtl`) from tobj.
        let text = String::from_utf8_lossy(crate::io::strip_bom(&bytes));
        let fail = |fault: ObjError| {
            self.fault.borrow_mut().get_or_insert(fault);
            Err(tobj::LoadError::MaterialParseError)
        };
        if let Some((number, message)) = text
            .lines()
            .enumerate()
            .find_map(|(i, line)| check_line(line).err().map(|e| (i + 1, e)))
        {
            return fail(ObjError::Line {
                path: file,
                line: number,
                message,
            });
        }
        match tobj::load_mtl_buf(&mut text.as_bytes()) {
            Ok((mut materials, names)) => {
                let dir = file.parent().unwrap_or(Path::new(""));
                for m in &mut materials {
                    m.diffuse_texture = m.diffuse_texture.as_deref().map(|t| {
                        let name = t.split_whitespace().next_back().unwrap_or(t);
                        let name = if t.starts_with('-') { name } else { t };
                        dir.join(name).to_string_lossy().into_owned()
                    });
                }
                Ok((materials, names))
            }
            Err(e) => fail(ObjError::Mesh {
                path: file,
                message: e.to_string(),
            }),
        }
    }
}

/// Checks one MTL line the way tobj reads it.
fn check_line(line: &str) -> Result<(), String> {
    let line = line.trim();
    let mut words = line.split_whitespace();
    let Some(keyword) = words.next() else {
        return Ok(());
    };
    let needs_argument = |len: usize| match line.get(len..).map(str::trim) {
        Some("") | None => Err(format!("`{keyword}` needs a file name")),
        Some(_) => Ok(()),
    };
    match keyword {
        "newmtl" if line[6..].trim().is_empty() => Err("`newmtl` needs a material name".to_owned()),
        "Ka" | "Kd" | "Ks" | "Ke" => {
            let max = crate::range::MAX_REFLECTANCE;
            let mut values = [0.0; 3];
            for (found, slot) in values.iter_mut().enumerate() {
                let word = words
                    .next()
                    .ok_or_else(|| format!("`{keyword}` needs 3 numbers, found {found}"))?;
                *slot = number(word, keyword)?;
            }
            finite(&values, "colour")?;
            match keyword {
                "Kd" | "Ks" => crate::range::within(&values, &format!("`{keyword}` value"), max),
                _ => Ok(()),
            }
        }
        "Ns" | "Ni" | "d" | "Tr" => {
            let word = words
                .next()
                .ok_or_else(|| format!("`{keyword}` needs a number"))?;
            finite(&[number(word, keyword)?], "value")
        }
        "map_Ka" | "map_Kd" | "map_Ks" | "map_Ns" | "map_ns" | "map_NS" => needs_argument(6),
        "map_Bump" | "map_bump" => needs_argument(8),
        "bump" => needs_argument(4),
        "map_d" => needs_argument(5),
        "illum" => match words.next().map(str::parse::<u8>) {
            Some(Ok(_)) => Ok(()),
            _ => Err("`illum` needs an illumination model number (0-255)".to_owned()),
        },
        _ => Ok(()),
    }
}

/// Fills the mesh's materials from the models' `usemtl`s, when any model has a known one.
pub(super) fn attach(mesh: &mut MeshData, models: &[tobj::Model], materials: &[tobj::Material]) {
    let known = |m: &tobj::Model| m.mesh.material_id.filter(|&i| i < materials.len());
    let used = |m: &&tobj::Model| !m.mesh.indices.is_empty();
    if !models.iter().filter(used).any(|m| known(m).is_some()) {
        return;
    }
    mesh.materials = materials.iter().map(mesh_material).collect();
    let default = materials.len() as u32;
    for m in models {
        let id = known(m).map_or(default, |i| i as u32);
        let count = m.mesh.indices.len() / 3;
        mesh.triangle_materials
            .extend(std::iter::repeat_n(id, count));
    }
    if mesh.triangle_materials.contains(&default) {
        mesh.materials.push(default_material());
    }
}

/// Returns the renderer's view of one MTL material (mapping in the module doc).
pub(super) fn mesh_material(m: &tobj::Material) -> MeshMaterial {
    let transparency = match (m.dissolve, m.unknown_param.get("Tr")) {
        (Some(d), _) => 1.0 - d,
        (None, Some(tr)) => tr.trim().parse().unwrap_or(0.0),
        (None, None) => 0.0,
    };
    MeshMaterial {
        name: m.name.clone(),
        kd: m.diffuse.map_or(Vec3::splat(0.6), Vec3::from_array),
        ks: m.specular.map_or(Vec3::ZERO, Vec3::from_array),
        shininess: m.shininess.unwrap_or(0.0).max(0.0),
        transparency: transparency.clamp(0.0, 1.0),
        ior: m
            .optical_density
            .filter(|&n| n > 0.0)
            .map_or(1.0, |n| n.min(crate::range::MAX_IOR as f32)),
        absorption: Vec3::ZERO,
        roughness: 0.0,
        texture: m.diffuse_texture.as_ref().map(PathBuf::from),
        emission: Vec3::ZERO,
        pbr: None,
    }
}

/// Returns the material given to faces that use none while others do: the renderer's grey.
pub(super) fn default_material() -> MeshMaterial {
    MeshMaterial {
        name: "(no usemtl)".to_owned(),
        kd: Vec3::splat(0.6),
        ks: Vec3::ZERO,
        shininess: 0.0,
        transparency: 0.0,
        ior: 1.0,
        absorption: Vec3::ZERO,
        roughness: 0.0,
        texture: None,
        emission: Vec3::ZERO,
        pbr: None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn checks_lines_as_tobj_reads_them() {
        for ok in [
            "",
            "# c",
            "newmtl red",
            "Kd 1 0 0",
            "Kd 1 0 0 9",
            "d 0.5",
            "map_Kd a b.png",
        ] {
            assert_eq!(check_line(ok), Ok(()), "{ok}");
        }
        let faults = [
            ("newmtl", "`newmtl` needs a material name"),
            ("Kd 0.5", "`Kd` needs 3 numbers, found 1"),
            ("Ks 1 x 1", "malformed number `x` in `Ks` line"),
            ("Ka 1 inf 1", "colour is not finite"),
            ("Ns", "`Ns` needs a number"),
            ("map_Kd   ", "`map_Kd` needs a file name"),
            (
                "illum 300",
                "`illum` needs an illumination model number (0-255)",
            ),
        ];
        for (line, message) in faults {
            assert_eq!(check_line(line), Err(message.to_owned()), "{line}");
        }
    }

    #[test]
    fn maps_dissolve_before_tr_and_sanitises_ior() {
        let mut m = tobj::Material {
            dissolve: Some(0.25),
            optical_density: Some(0.0),
            ..Default::default()
        };
        m.unknown_param.insert("Tr".to_owned(), "0.5".to_owned());
        let mapped = mesh_material(&m);
        assert_eq!((mapped.transparency, mapped.ior), (0.75, 1.0));
        m.dissolve = None;
        assert_eq!(mesh_material(&m).transparency, 0.5);
        assert_eq!(mesh_material(&m).kd, Vec3::splat(0.6));
    }
}
