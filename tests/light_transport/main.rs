//! Light transport: the images the integrators make, against closed forms and each other.
//! Parts: `shading` (the first renderer's Phong light), `dielectric` (refraction), `materials`
//! (textures and normal maps), `convergence` and `furnace` (light neither lost nor gained),
//! `media` (the camera inside solids, relative indices, absorption), `leaks` (no light through
//! closed walls), `deep_paths` (Russian roulette past any fixed depth), `shadow_media` (no
//! shadow rays from inside transparent solids), `weak_branches` (weak reflections shared by a
//! pixel's samples), `shared_caustics` (caustic estimates shared by a pixel's samples), `progressive` (the progressive integrator), `effect_plan` (the effects
//! decided before the passes), `pixel_sampling` (determinism, crops, tiles, adaptive sampling),
//! `spot_and_directional` (those lights' shadows and photons), `adaptive_pixels` (samples
//! where the half-buffers see noise), `time_planner` (`--time-budget` and `--target-error` for
//! photon mapping) and `final_scene`.

#[path = "../common/mod.rs"]
mod common;

mod adaptive_pixels;
mod convergence;
mod deep_paths;
mod dielectric;
mod effect_plan;
mod final_scene;
mod furnace;
mod leaks;
mod materials;
mod media;
mod pixel_sampling;
mod progressive;
mod shading;
mod shadow_media;
mod shared_caustics;
mod spot_and_directional;
mod time_planner;
mod weak_branches;
