//! `gr.settings{...}`: a scene's own render settings, the defaults of `caustic render`'s
//! quality flags for the `gr.render` calls after it.
//!
//! ```lua
//! gr.settings{gather_rays = 4, caustic_photons = 4000000, light_samples = 2}
//! ```
//!
//! Why in the scene: Mitsuba's and pbrt's scene files carry their sampler and integrator, so a
//! scene renders as its author tuned it with no flags to remember; a scene with a 2M-triangle
//! water surface whose floor is lit only through it needs other budgets than a Cornell box.
//! The command line still wins: a flag given there overrides the scene's value, and photon counts
//! set here still follow the image (`--scale 0.25` traces a sixteenth) unless `--photons`,
//! `--caustic-photons` or `--photon-scale` is on the command line.
//!
//! Each key is a flag's name with `_` for `-`; a number or string is the flag's value, `true`
//! gives a switch (`adaptive = true` is `--adaptive`), `false` leaves it off. Only flags that set
//! how an image is computed are accepted ([`KEYS`]): where an image goes, its size, the threads and
//! the seed are the command line's. The values are checked by `caustic render`'s own parser when
//! the image renders, so a bad one is reported with the flag's usual message.

use super::State;
use crate::lua::args::{Args, type_name};
use mlua::Value;

/// The keys `gr.settings` accepts; switches (no value) are marked `true`.
pub const KEYS: &[(&str, bool)] = &[
    ("spp", false),
    ("adaptive", true),
    ("aa_threshold", false),
    ("aa_depth", false),
    ("noise_target", false),
    ("max_spp", false),
    ("light_samples", false),
    ("gi", false),
    ("photons", false),
    ("caustic_photons", false),
    ("photon_k", false),
    ("indirect", false),
    ("gather_rays", false),
    ("gather_lookup", false),
    ("irradiance_cache", false),
    ("cache_accuracy", false),
    ("cache_rays", false),
    ("tonemap", false),
    ("exposure", false),
    ("integrator", false),
    ("passes", false),
    ("alpha", false),
    ("radius", false),
    ("local_radii", false),
    ("target_error", false),
    ("time_budget", false),
];

/// `gr.settings(table)`: records the table's flags for the renders that follow.
pub(super) fn settings(s: &mut State, a: &Args) -> mlua::Result<()> {
    let table = match a.get(1) {
        Some(Value::Table(t)) => t.clone(),
        other => {
            let got = other.map_or("no value".to_string(), type_name);
            return Err(a.bad(1, format!("table expected, got {got}")));
        }
    };
    let listed = || KEYS.iter().map(|(k, _)| *k).collect::<Vec<_>>().join(", ");
    for pair in table.pairs::<Value, Value>() {
        let (key, value) = pair?;
        let Value::String(key) = key else {
            return Err(a.bad(1, format!("keys must be setting names ({})", listed())));
        };
        let key = key.to_str()?.to_string();
        let Some(&(_, switch)) = KEYS.iter().find(|(k, _)| *k == key) else {
            return Err(a.bad(
                1,
                format!("unknown setting '{key}' (the settings are {})", listed()),
            ));
        };
        let flag = format!("--{}", key.replace('_', "-"));
        let tokens = match (&value, switch) {
            (Value::Boolean(true), true) => vec![flag],
            (Value::Boolean(false), true) => Vec::new(),
            (Value::Integer(i), false) => vec![flag, i.to_string()],
            (Value::Number(x), false) if x.is_finite() => {
                // Whole numbers as integers, so counts such as 4e6 parse as counts.
                let text = if x.fract() == 0.0 && x.abs() < 2f64.powi(63) {
                    format!("{}", *x as i64)
                } else {
                    format!("{x}")
                };
                vec![flag, text]
            }
            (Value::String(t), false) => vec![flag, t.to_str()?.to_string()],
            (v, true) => {
                return Err(a.bad(
                    1,
                    format!("'{key}' is a switch: true or false, got {}", type_name(v)),
                ));
            }
            (v, false) => {
                return Err(a.bad(
                    1,
                    format!(
                        "'{key}' must be a finite number or a string, got {}",
                        type_name(v)
                    ),
                ));
            }
        };
        s.desc.settings.retain(|(k, _)| *k != key);
        s.desc.settings.push((key, tokens));
    }
    Ok(())
}
