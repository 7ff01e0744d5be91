//! Lua scenes: what a scene script may do and what it makes. Parts: `gr_api` (the `gr` API's
//! semantics and errors), `sandbox` (what a script may not reach), `memory_limit` (a script
//! that exhausts its Lua state's memory), `memory_budget` (what a scene creates, charged),
//! `water_mesh_and_settings` (meshes and settings a scene generates), `gltf_nodes`
//! (`gr.gltf`: a glTF file's hierarchy as nodes), `legacy_dialect` and
//! `legacy_detection` (scripts for the course's legacy API), and `script_fuzz` (scripts and glTF
//! structures generated from the grammar; `tools/fuzz.sh` runs its properties).
//!
//! `memory_limit` shares this binary safely: the limit it exhausts is one Lua state's
//! (`ScriptOptions::memory_limit`, 64 MiB), not the process's. No part sets process-wide state:
//! environment variables and folders are given to child processes only.

#[path = "../common/mod.rs"]
mod common;

mod gltf_nodes;
mod gr_api;
mod legacy_detection;
mod legacy_dialect;
mod memory_budget;
mod memory_limit;
mod sandbox;
mod script_fuzz;
mod water_mesh_and_settings;
