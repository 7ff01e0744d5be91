//! Files and output: what caustic reads and writes. Parts: `image_formats` and `mesh_formats`
//! (formats in and out), `gltf_scenes` and `gltf_textures` (glTF files as scenes, their
//! textures), `input_quirks` (what real tools write, and numeric ranges),
//! `photon_map_files` (saved photon maps, and a photon pass in parts), `progressive_parts`
//! (progressive passes rendered apart and merged), `mitsuba_export`, `stitch_tiles` (crafted tiles),
//! `filesystem` (symlinks, permissions, special files, a process killed while writing),
//! `hostile` (files that cannot be turned against the user) and `loader_fuzz` (the loaders'
//! byte mutations; `tools/fuzz.sh` runs its properties and `hostile`'s `fuzz_` ones).
//!
//! Process-wide state, and why it is safe here: `hostile` installs this binary's global
//! allocator, which records the largest allocation of a thread only while that thread asks
//! (`largest_allocation`), so the other parts' allocations are neither counted nor changed;
//! `filesystem` runs this binary again as a child that kills itself with SIGTERM, filtered to
//! its one test by its full name.

#[path = "../common/mod.rs"]
mod common;

mod filesystem;
mod gltf_scenes;
mod gltf_textures;
mod hostile;
mod image_formats;
mod input_quirks;
mod loader_fuzz;
mod mesh_formats;
mod mitsuba_export;
mod photon_map_files;
mod progressive_parts;
mod stitch_tiles;
