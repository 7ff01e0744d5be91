//! The images a glTF file's materials use: where each one's bytes are (a buffer view of the GLB
//! binary chunk or of any buffer, a base64 `data:` URI, or a file beside the glTF file), and the
//! mean colour of an emissive texture, which an emitter's one radiance stands in for.
//!
//! Embedded bytes are copied out of their buffer once per image, shared by every material that
//! uses it, and charged to the load's account; they are decoded by the scene build
//! ([`crate::scene::images`]), which charges the decoded pixels. Every fault is a message naming
//! the image, which the caller prefixes with the material and the texture, and the loader with
//! the file.

use super::buffer::{Buffer, decode_data_uri, uri_path};
use crate::budget::Account;
use crate::geometry::mesh::ImageSource;
use crate::material::texture::{Texture, header_size};
use glam::Vec3;
use std::borrow::Cow;
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// Where one image's bytes are.
enum Bytes<'a> {
    /// Inside the glTF file: a buffer view's bytes, or a decoded `data:` URI.
    Embedded(Cow<'a, [u8]>),
    /// A file beside it.
    File(PathBuf),
}

/// The images of one glTF document, found as its materials ask for them.
pub(super) struct Images<'a> {
    doc: &'a gltf::Document,
    buffers: &'a [Buffer<'a>],
    /// The glTF file, which embedded images name.
    path: &'a Path,
    /// The folder relative URIs are resolved against.
    dir: &'a Path,
    account: &'a Account,
    /// Each image found so far, by image index.
    sources: HashMap<usize, ImageSource>,
    /// The linear mean colour of each emissive image decoded so far, by image index.
    means: HashMap<usize, Vec3>,
}

impl<'a> Images<'a> {
    /// Returns the images of `doc`, the file at `path` (in `dir`) whose buffers are `buffers`;
    /// embedded bytes copied out are charged to `account`.
    pub fn new(
        doc: &'a gltf::Document,
        buffers: &'a [Buffer<'a>],
        path: &'a Path,
        dir: &'a Path,
        account: &'a Account,
    ) -> Images<'a> {
        Images {
            doc,
            buffers,
            path,
            dir,
            account,
            sources: HashMap::new(),
            means: HashMap::new(),
        }
    }

    /// Returns the bytes of `image`, or the file it names; a buffer view outside its buffer,
    /// a `data:` URI that is not base64, bad base64 and an image with neither a view nor a URI
    /// are errors naming the image.
    ///
    /// The image's JSON is read rather than `gltf::Image::source`, which panics on a buffer
    /// view without a MIME type (caustic guesses the format from the bytes).
    fn bytes(&self, image: &gltf::Image) -> Result<Bytes<'a>, String> {
        let i = image.index();
        let json = &self.doc.as_json().images[i];
        if let Some(index) = &json.buffer_view {
            let view = self.doc.views().nth(index.value()).ok_or_else(|| {
                format!("image {i}: buffer view {} does not exist", index.value())
            })?;
            let buffers: &'a [Buffer<'a>] = self.buffers;
            let buffer = buffers.get(view.buffer().index());
            let len = buffer.map_or(0, Buffer::len);
            let end = view.offset().checked_add(view.length());
            return match (buffer, end.filter(|&end| end <= len)) {
                (Some(buffer), Some(_)) => buffer
                    .read(view.offset(), view.length())
                    .map(Bytes::Embedded)
                    .map_err(|e| format!("image {i}: {e}")),
                _ => Err(format!(
                    "image {i}: buffer view {} (bytes {}..+{}) lies outside buffer {} ({} bytes)",
                    view.index(),
                    view.offset(),
                    view.length(),
                    view.buffer().index(),
                    len
                )),
            };
        }
        let Some(uri) = &json.uri else {
            return Err(format!("image {i} has neither a buffer view nor a uri"));
        };
        match uri.strip_prefix("data:") {
            Some(data) => decode_data_uri(data)
                .map(|b| Bytes::Embedded(Cow::Owned(b)))
                .map_err(|e| format!("image {i}: {e}")),
            None => Ok(Bytes::File(
                uri_path(uri, self.dir).unwrap_or_else(|| self.dir.join(uri)),
            )),
        }
    }

    /// Returns where the image `texture` shows is: a file, or its embedded bytes (copied once
    /// per image and charged to the account).
    pub fn source(&mut self, texture: &gltf::Texture) -> Result<ImageSource, String> {
        let image = texture.source();
        let i = image.index();
        if let Some(source) = self.sources.get(&i) {
            return Ok(source.clone());
        }
        let source = match self.bytes(&image)? {
            Bytes::File(path) => ImageSource::File(path),
            Bytes::Embedded(bytes) => {
                let what = format!("image {i} ({} encoded bytes)", bytes.len());
                self.account
                    .try_charge(bytes.len() as u64, what)
                    .map_err(|e| e.to_string())?;
                ImageSource::Embedded {
                    file: self.path.to_owned(),
                    image: i,
                    bytes: Arc::from(bytes.into_owned()),
                }
            }
        };
        self.sources.insert(i, source.clone());
        Ok(source)
    }

    /// Returns the mean linear colour of the sRGB-encoded image `texture` shows (an emissive
    /// texture), decoded for the purpose and dropped, its pixels charged meanwhile. An embedded
    /// image that cannot be decoded is an error; an image file that cannot be read or decoded
    /// is a warning, and `None`: the factors alone then make the radiance.
    pub fn srgb_mean(&mut self, texture: &gltf::Texture) -> Result<Option<Vec3>, String> {
        let image = texture.source();
        let i = image.index();
        if let Some(mean) = self.means.get(&i) {
            return Ok(Some(*mean));
        }
        let decoded = match self.bytes(&image)? {
            Bytes::Embedded(bytes) => self.decode(&bytes).map_err(|e| format!("image {i}: {e}"))?,
            Bytes::File(path) => {
                let read = self
                    .account
                    .read_scope()
                    .check(&path)
                    .and_then(|()| crate::files::read_regular(&path))
                    .map_err(|e| format!("cannot read {}: {e}", path.display()))
                    .and_then(|bytes| self.decode(&bytes));
                match read {
                    Ok(t) => t,
                    Err(e) => {
                        eprintln!(
                            "warning: {}: emissive image {i}: {e}; the emissive factor alone \
                             is the radiance",
                            self.path.display()
                        );
                        return Ok(None);
                    }
                }
            }
        };
        let mean = decoded.srgb_mean().into();
        self.means.insert(i, mean);
        Ok(Some(mean))
    }

    /// Decodes encoded image `bytes`, its decoded size charged to a scratch account of the
    /// load's budget while it decodes (the texture lives only until its mean is taken).
    fn decode(&self, bytes: &[u8]) -> Result<Texture, String> {
        let scratch = self.account.budget().account();
        let reader = image::ImageReader::new(std::io::Cursor::new(bytes));
        if let Some((w, h, size)) = header_size(reader) {
            scratch
                .try_charge(size, format!("{w}x{h} pixels decoded"))
                .map_err(|e| e.to_string())?;
        }
        Texture::decode(bytes)
    }
}
