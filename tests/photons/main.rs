//! Photons: the photon map and what photon mapping estimates. Parts: `map_queries` (k-nearest
//! and radius queries against brute force, quantisation, build determinism), `degenerate_search`
//! (queries on flat, coincident, single and empty photon sets) and `closed_forms` (photon
//! mapping's irradiance and caustics against closed forms).

#[path = "../common/mod.rs"]
mod common;

mod closed_forms;
mod degenerate_search;
mod map_queries;
