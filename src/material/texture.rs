//! Image textures: colour maps that replace `kd`, and bump maps (RGB normal maps or grey height
//! maps) that bend the shading normal; the decoding of image files and of images embedded in
//! mesh files, whose size the decoder bounds.
//!
//! ```lua
//! brick = gr.material({0.1, 0.7, 0.1}, {0, 0, 0}, 0, 0, 0, 0, 'Assets/brick.png', 'Assets/brick_norm.png')
//! ```
//!
//! Conventions:
//! - `(u, v)` in [0, 1]² with `v = 0` at the image's top row (the original project's convention);
//!   coordinates outside wrap around (repeat).
//! - Lookups are bilinear between the four nearest texel centres.
//! - Texel bytes are used as linear values `c/255`, exactly as the course uses colours (no gamma)
//!   ([`Texture::colour`]); glTF's colour textures are sRGB-encoded and read through the sRGB
//!   curve instead ([`Texture::srgb_colour`]), each texel decoded before the filter blends them.
//! - A normal map stores a tangent-space normal: red along +u, green along "up" in the image
//!   (towards decreasing v), blue along the surface normal, each byte decoded as `(c − 128)/127`
//!   so that (128, 128, 255) is exactly the unperturbed normal.
//! - A bump image whose texels are all grey is a height map instead: its slopes (central
//!   differences, one texel apart) tilt the normal, a rise of 1/8 of full scale per texel giving
//!   45°.
//! - A glTF normal texture ([`BumpMap::Scaled`]) decodes a byte as `2c/255 − 1`, as glTF
//!   defines it, with x and y multiplied by the texture's `scale`.
//! - Decoding ([`Texture::load`], [`Texture::decode`]) keeps the image crate's default limits: it
//!   refuses an image whose decoded pixels would take more than 512 MiB. The caller charges the
//!   memory budget from the header's size first ([`header_size`]).

use crate::error::{Error, Loc, Result};
use glam::{Vec2, Vec3A};
use std::io::{BufRead, Seek};
use std::path::Path;
use std::sync::{Arc, LazyLock};

/// An 8-bit RGB image kept in memory for lookups.
#[derive(Clone, Debug, PartialEq)]
pub struct Texture {
    pub width: u32,
    pub height: u32,
    /// Row-major RGB bytes, row 0 at the top.
    texels: Vec<[u8; 3]>,
}

/// How a bump image bends the normal.
#[derive(Clone, Debug, PartialEq)]
pub enum BumpMap {
    /// An RGB tangent-space normal map.
    Normal(Texture),
    /// A grey height map.
    Height(Texture),
    /// A glTF normal texture: tangent-space normals coded `2c/255 − 1`, x and y times `scale`.
    Scaled { texture: Arc<Texture>, scale: f32 },
}

/// Slope multiplier of height maps: a full-scale rise over 8 texels tilts the normal by 45°.
const HEIGHT_SLOPE: f32 = 8.0;

impl Texture {
    /// Loads a PNG or JPEG image; errors name the file and the script line at `loc`.
    pub fn load(path: &Path, loc: &Loc) -> Result<Texture> {
        let img = crate::files::check_regular(path)
            .and_then(|()| image::ImageReader::open(path))
            .and_then(|r| r.with_guessed_format())
            .map_err(|e| Error::at(loc, format!("cannot read texture {}: {e}", path.display())))?
            .decode()
            .map_err(|e| {
                Error::at(
                    loc,
                    format!("cannot decode texture {}: {e}", path.display()),
                )
            })?
            .to_rgb8();
        Texture::from_image(img)
            .ok_or_else(|| Error::at(loc, format!("texture {} is empty", path.display())))
    }

    /// Decodes encoded PNG or JPEG `bytes` (an image embedded in a mesh file); the error says
    /// what is wrong, for the caller to prefix with the file and the image.
    pub fn decode(bytes: &[u8]) -> std::result::Result<Texture, String> {
        let img = image::ImageReader::new(std::io::Cursor::new(bytes))
            .with_guessed_format()
            .map_err(|e| format!("cannot read: {e}"))?
            .decode()
            .map_err(|e| format!("cannot decode: {e}"))?
            .to_rgb8();
        Texture::from_image(img).ok_or_else(|| "the image is empty".to_owned())
    }

    /// Returns the texture of a decoded RGB image, or `None` when it has no pixels.
    fn from_image(img: image::RgbImage) -> Option<Texture> {
        (img.width() > 0 && img.height() > 0).then(|| {
            Texture::from_rgb(
                img.width(),
                img.height(),
                img.pixels().map(|p| p.0).collect(),
            )
        })
    }

    /// Returns a texture from row-major RGB texels (`width × height` of them, both non-zero).
    pub fn from_rgb(width: u32, height: u32, texels: Vec<[u8; 3]>) -> Texture {
        assert_eq!(
            texels.len(),
            width as usize * height as usize,
            "texel count must match the size"
        );
        Texture {
            width,
            height,
            texels,
        }
    }

    /// Returns the bilinearly filtered texel bytes (0–255 per channel) at `uv`, the image
    /// repeating in both directions.
    ///
    /// The four texels' coordinates are wrapped once (the second of each pair is the first plus
    /// one, or 0 at the edge): wrapping each of the eight with `rem_euclid`, an integer division,
    /// made this function 8% of the final scene's photon-pass samples. A huge `uv`, whose
    /// floor saturates at `i64::MAX`, no longer overflows adding one.
    fn bilinear_bytes(&self, uv: Vec2) -> Vec3A {
        self.bilinear(uv, |[r, g, b]| Vec3A::new(r as f32, g as f32, b as f32))
    }

    /// Returns the bilinear blend at `uv` of the four nearest texels, each read by `texel`
    /// (see [`Texture::bilinear_bytes`] for the wrapping).
    #[inline]
    fn bilinear(&self, uv: Vec2, texel: impl Fn([u8; 3]) -> Vec3A) -> Vec3A {
        let x = uv.x * self.width as f32 - 0.5;
        let y = uv.y * self.height as f32 - 0.5;
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = (x - x0, y - y0);
        let (w, h) = (i64::from(self.width), i64::from(self.height));
        let (x0, y0) = ((x0 as i64).rem_euclid(w), (y0 as i64).rem_euclid(h));
        let next = |c: i64, n: i64| if c + 1 == n { 0 } else { c + 1 };
        let (x1, y1) = (next(x0, w), next(y0, h));
        let texel =
            |x: i64, y: i64| texel(self.texels[y as usize * self.width as usize + x as usize]);
        let top = texel(x0, y0) * (1.0 - fx) + texel(x1, y0) * fx;
        let bottom = texel(x0, y1) * (1.0 - fx) + texel(x1, y1) * fx;
        top * (1.0 - fy) + bottom * fy
    }

    /// Returns the colour at `uv` in [0, 1] per channel.
    pub fn colour(&self, uv: Vec2) -> Vec3A {
        self.bilinear_bytes(uv) / 255.0
    }

    /// Returns the colour at `uv` of an sRGB-encoded image, decoded to linear values in
    /// `[0, 1]`: each texel through the sRGB curve ([`srgb_to_linear`]), then the filter.
    pub fn srgb_colour(&self, uv: Vec2) -> Vec3A {
        let table = &*SRGB_TABLE;
        self.bilinear(uv, |[r, g, b]| {
            Vec3A::new(table[r as usize], table[g as usize], table[b as usize])
        })
    }

    /// Returns the texels of an sRGB-encoded image decoded to linear values, row-major from
    /// the top row: what [`Texture::srgb_colour`] filters between.
    pub fn srgb_texels(&self) -> Vec<Vec3A> {
        let table = &*SRGB_TABLE;
        self.texels
            .iter()
            .map(|&[r, g, b]| Vec3A::new(table[r as usize], table[g as usize], table[b as usize]))
            .collect()
    }

    /// Returns the mean over the texels of an sRGB-encoded image, decoded to linear values.
    pub fn srgb_mean(&self) -> Vec3A {
        let table = &*SRGB_TABLE;
        let sum: glam::DVec3 = self
            .texels
            .iter()
            .map(|t| glam::DVec3::from_array(t.map(|c| f64::from(table[c as usize]))))
            .sum();
        (sum / self.texels.len() as f64).as_vec3a()
    }

    /// Returns true when every texel is grey (R = G = B).
    pub fn is_grey(&self) -> bool {
        self.texels.iter().all(|t| t[0] == t[1] && t[1] == t[2])
    }
}

impl BumpMap {
    /// Returns the bump map an image stands for: grey images are height maps.
    pub fn from_texture(t: Texture) -> BumpMap {
        if t.is_grey() {
            BumpMap::Height(t)
        } else {
            BumpMap::Normal(t)
        }
    }

    /// Returns the tangent-space normal at `uv` (x along +u, y towards decreasing v, z along n).
    pub fn tangent_normal(&self, uv: Vec2) -> Vec3A {
        match self {
            BumpMap::Normal(t) => {
                let c = ((t.bilinear_bytes(uv) - Vec3A::splat(128.0)) / 127.0)
                    .clamp(Vec3A::splat(-1.0), Vec3A::ONE);
                c.normalize_or(Vec3A::Z)
            }
            BumpMap::Scaled { texture, scale } => {
                let c = texture.bilinear_bytes(uv) * (2.0 / 255.0) - Vec3A::ONE;
                (c * Vec3A::new(*scale, *scale, 1.0)).normalize_or(Vec3A::Z)
            }
            BumpMap::Height(t) => {
                let (du, dv) = (1.0 / t.width as f32, 1.0 / t.height as f32);
                let h = |u: f32, v: f32| t.bilinear_bytes(Vec2::new(u, v)).x / 255.0;
                let slope_u = (h(uv.x + du, uv.y) - h(uv.x - du, uv.y)) * 0.5 * HEIGHT_SLOPE;
                // "Up" in the image is decreasing v.
                let slope_up = (h(uv.x, uv.y - dv) - h(uv.x, uv.y + dv)) * 0.5 * HEIGHT_SLOPE;
                Vec3A::new(-slope_u, -slope_up, 1.0).normalize()
            }
        }
    }
}

/// Returns the linear value of an sRGB-encoded one in `[0, 1]` (IEC 61966-2-1).
pub fn srgb_to_linear(c: f32) -> f32 {
    if c <= 0.040_45 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// The linear value of each sRGB byte.
static SRGB_TABLE: LazyLock<[f32; 256]> =
    LazyLock::new(|| std::array::from_fn(|c| srgb_to_linear(c as f32 / 255.0)));

/// Returns the width and height an encoded image's header gives, and the bytes decoding it
/// takes: its decoded pixels and the RGB copy kept; `None` when the header cannot be read
/// (decoding then fails with the reason).
pub fn header_size<R: BufRead + Seek>(reader: image::ImageReader<R>) -> Option<(u32, u32, u64)> {
    use image::ImageDecoder;
    let decoder = reader.with_guessed_format().ok()?.into_decoder().ok()?;
    let (w, h) = decoder.dimensions();
    let rgb = u64::from(w) * u64::from(h) * 3;
    Some((w, h, decoder.total_bytes().saturating_add(rgb)))
}

/// Returns `n` bent by the tangent-space normal `ts`, in the frame built from the surface's
/// `dpdu` (the tangent: +u), the "up" vector `n × tangent` and `n`.
pub fn apply_tangent_normal(n: Vec3A, dpdu: Vec3A, ts: Vec3A) -> Vec3A {
    let t = (dpdu - n * n.dot(dpdu)).normalize_or_zero();
    let t = if t == Vec3A::ZERO {
        n.any_orthonormal_vector()
    } else {
        t
    };
    let b = n.cross(t);
    (t * ts.x + b * ts.y + n * ts.z).normalize_or(n)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn checker() -> Texture {
        // 2 × 2: red, green / blue, white.
        Texture::from_rgb(
            2,
            2,
            vec![[255, 0, 0], [0, 255, 0], [0, 0, 255], [255, 255, 255]],
        )
    }

    /// The filter equals the definition (each of the four texels wrapped on its own, in i128 so
    /// that nothing overflows) bit for bit: across edges, at negative and huge `uv`, on a texture
    /// whose sides are not powers of two.
    #[test]
    fn bilinear_equals_wrapping_each_texel() {
        let (w, h) = (5u32, 3u32);
        let texels: Vec<[u8; 3]> = (0..w * h)
            .map(|i| {
                [
                    (i * 37 % 256) as u8,
                    (i * 91 % 256) as u8,
                    (i * 13 % 256) as u8,
                ]
            })
            .collect();
        let t = Texture::from_rgb(w, h, texels.clone());
        let reference = |uv: Vec2| {
            let x = uv.x * w as f32 - 0.5;
            let y = uv.y * h as f32 - 0.5;
            let (x0, y0) = (x.floor(), y.floor());
            let (fx, fy) = (x - x0, y - y0);
            let (x0, y0) = (x0 as i64 as i128, y0 as i64 as i128);
            let texel = |x: i128, y: i128| {
                let (x, y) = (x.rem_euclid(w as i128), y.rem_euclid(h as i128));
                let [r, g, b] = texels[(y * w as i128 + x) as usize];
                Vec3A::new(r as f32, g as f32, b as f32)
            };
            let top = texel(x0, y0) * (1.0 - fx) + texel(x0 + 1, y0) * fx;
            let bottom = texel(x0, y0 + 1) * (1.0 - fx) + texel(x0 + 1, y0 + 1) * fx;
            top * (1.0 - fy) + bottom * fy
        };
        let mut uvs = vec![
            Vec2::new(1e30, -1e30),
            Vec2::new(-1e30, 1e30),
            Vec2::new(0.999_999, 0.999_999),
            Vec2::new(0.0, 0.0),
            Vec2::new(-0.1, 1.1),
        ];
        for k in 0..20_000 {
            let f = k as f32;
            uvs.push(Vec2::new((f * 0.731).sin() * 4.0, (f * 0.377).cos() * 3.0));
        }
        for uv in uvs {
            let (got, want) = (t.bilinear_bytes(uv), reference(uv));
            assert_eq!(
                got.to_array().map(f32::to_bits),
                want.to_array().map(f32::to_bits),
                "{uv}"
            );
        }
    }

    #[test]
    fn lookups_at_texel_centres_and_between_them() {
        let t = checker();
        assert_eq!(
            t.colour(Vec2::new(0.25, 0.25)),
            Vec3A::new(1.0, 0.0, 0.0),
            "top-left texel, v = 0 at the top"
        );
        assert_eq!(t.colour(Vec2::new(0.75, 0.75)), Vec3A::ONE);
        // Half-way between red and green.
        let mid = t.colour(Vec2::new(0.5, 0.25));
        assert!((mid - Vec3A::new(0.5, 0.5, 0.0)).length() < 1e-6, "{mid}");
        // Wrap-around: u = 1.25 is u = 0.25.
        assert_eq!(
            t.colour(Vec2::new(1.25, 0.25)),
            t.colour(Vec2::new(0.25, 0.25))
        );
        // The centre of the image averages all four.
        let c = t.colour(Vec2::new(0.5, 0.5));
        assert!((c - Vec3A::new(0.5, 0.5, 0.5)).length() < 1e-6);
    }

    #[test]
    fn flat_maps_leave_the_normal_alone_and_tilted_ones_tilt_it() {
        let flat = BumpMap::from_texture(Texture::from_rgb(1, 1, vec![[128, 128, 255]]));
        assert_eq!(flat.tangent_normal(Vec2::new(0.3, 0.8)), Vec3A::Z);
        let n = Vec3A::new(0.0, 0.6, 0.8);
        assert_eq!(apply_tangent_normal(n, Vec3A::X, Vec3A::Z), n);
        // A normal map pointing along +u tilts the normal towards the tangent.
        let tilted = BumpMap::from_texture(Texture::from_rgb(1, 1, vec![[255, 128, 128]]));
        let ts = tilted.tangent_normal(Vec2::ZERO);
        assert!((ts - Vec3A::X).length() < 1e-6, "{ts}");
        assert!((apply_tangent_normal(Vec3A::Z, Vec3A::X, ts) - Vec3A::X).length() < 1e-6);
        // Constant height: flat. A ramp rising along +u tilts towards -u.
        let level =
            BumpMap::from_texture(Texture::from_rgb(2, 1, vec![[90, 90, 90], [90, 90, 90]]));
        assert_eq!(level.tangent_normal(Vec2::new(0.5, 0.5)), Vec3A::Z);
        let ramp: Vec<[u8; 3]> = (0..8).map(|i| [(i * 30) as u8; 3]).collect();
        let ramp = BumpMap::from_texture(Texture::from_rgb(8, 1, ramp));
        assert!(matches!(ramp, BumpMap::Height(_)));
        let n = ramp.tangent_normal(Vec2::new(0.5, 0.5));
        assert!(n.x < -0.5 && n.y.abs() < 1e-6, "{n}");
    }

    /// sRGB bytes decode by the standard curve before the filter blends them, and their mean
    /// is the linear mean; a glTF normal map decodes `2c/255 − 1` and scales x and y.
    #[test]
    fn srgb_colours_and_scaled_normal_maps_decode_as_gltf_defines() {
        assert!((srgb_to_linear(188.0 / 255.0) - 0.502_886).abs() < 1e-6);
        assert_eq!(srgb_to_linear(0.0), 0.0);
        assert!((srgb_to_linear(1.0) - 1.0).abs() < 1e-6);
        let t = Texture::from_rgb(2, 1, vec![[255, 188, 0], [0, 188, 0]]);
        // Half-way between the texels: the mean of the decoded values, not the decoded mean.
        let mid = t.srgb_colour(Vec2::new(0.5, 0.5));
        assert!(
            (mid - Vec3A::new(0.5, 0.502_886, 0.0)).length() < 1e-6,
            "{mid}"
        );
        assert!((t.srgb_mean() - mid).length() < 1e-6);
        let map = |scale: f32| BumpMap::Scaled {
            texture: Arc::new(Texture::from_rgb(1, 1, vec![[255, 0, 255]])),
            scale,
        };
        let n = map(1.0).tangent_normal(Vec2::ZERO);
        assert!(
            (n - Vec3A::new(1.0, -1.0, 1.0).normalize()).length() < 1e-6,
            "{n}"
        );
        let n = map(0.5).tangent_normal(Vec2::ZERO);
        assert!(
            (n - Vec3A::new(0.5, -0.5, 1.0).normalize()).length() < 1e-6,
            "{n}"
        );
    }

    #[test]
    fn unreadable_textures_name_the_file_and_line() {
        let loc = Loc {
            file: "scene.lua".into(),
            line: 7,
        };
        let e = Texture::load(Path::new("/nonexistent/t.png"), &loc)
            .unwrap_err()
            .to_string();
        assert!(
            e.starts_with("scene.lua:7: cannot read texture /nonexistent/t.png"),
            "{e}"
        );
        let dir = std::env::temp_dir().join(format!("caustic-tex-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let bad = dir.join("bad.png");
        std::fs::write(&bad, b"\x89PNG\r\n\x1a\nnot really").unwrap();
        let e = Texture::load(&bad, &loc).unwrap_err().to_string();
        assert!(e.starts_with("scene.lua:7: cannot decode texture"), "{e}");
        let _ = std::fs::remove_dir_all(dir);
    }
}
