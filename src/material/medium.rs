//! Which medium a ray travels in, across nested and touching dielectrics.
//!
//! A ray carries a small stack of the transparent solids it is inside (each with its index of
//! refraction); the outside world is air (index 1). Where solids overlap — a glass ball resting in
//! water, a ball half under a water surface — the medium is the one with the **highest index** among
//! those the ray is inside (Schmidt and Budge, "Simple Nested Dielectrics in Ray Traced Images",
//! 2002, with index as the priority). Crossing the boundary of a solid that does not win is a
//! *false* interface: the stack changes but the ray goes straight on with no reflection.
//!
//! # What `ior` means
//! An index of 1 or more is **absolute** (against vacuum), and the medium outside a surface is
//! whatever contains it: glass (1.5) in water (1.33) refracts by 1.5/1.33. An index **below 1 is
//! relative to the medium the solid sits in**, as Cycles, LuxCore and Mitsuba users write an air
//! bubble in water (`ior = 0.75`, that is 1/1.33): entering it, the ray's index becomes the
//! container's times that ratio, and such a solid wins over every absolute one it overlaps (a
//! bubble is a hole in the water, whatever the water's index), the one entered last winning
//! among several. An air bubble cannot be an absolute index of 1 inside water: the denser water
//! would win and the bubble vanish; `caustic` warns about that case where the scene is built.
//!
//! # Absorption
//! The winning solid's material also says how the medium absorbs ([`crate::material::Material::absorption`]):
//! a ray segment of length `d` in it keeps `exp(−σ·d)` of its light (Beer–Lambert).
//!
//! Eye rays, photons and gather rays use the same stack, so all see the same interfaces; a path
//! starts in the medium of its origin (the camera's, a light's: [`crate::scene::Scene::media_at`]).

/// Most overlapping solids tracked; deeper nesting treats further entries as air.
const DEPTH: usize = 8;

/// One solid a ray is inside.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
struct Entry {
    /// The solid's material index in the scene.
    id: u32,
    /// Its absolute index (a relative one already multiplied by its container's).
    ior: f32,
    /// Whether the material gave a relative index (below 1): such a solid wins over absolute ones.
    relative: bool,
}

/// The transparent solids a ray is inside, by material id.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct MediumStack {
    entries: [Entry; DEPTH],
    len: u8,
}

/// What happens where a ray crosses the boundary of a transparent solid.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Crossing {
    /// Index on the side the ray comes from.
    pub n_from: f32,
    /// Index on the side the ray goes to.
    pub n_to: f32,
    /// The stack beyond the boundary.
    pub after: MediumStack,
}

impl Crossing {
    /// Returns true when the media on both sides have one index (a false interface): no
    /// reflection, no bending; the stack beyond still says which medium absorbs.
    pub fn is_false(&self) -> bool {
        self.n_from == self.n_to
    }
}

impl MediumStack {
    /// Returns the stack of a ray in air.
    pub fn air() -> MediumStack {
        MediumStack::default()
    }

    /// Returns true when the ray is inside no transparent solid.
    pub fn is_air(&self) -> bool {
        self.len == 0
    }

    /// Returns the entry whose medium the ray is in: the last relative one entered, else the
    /// absolute one of highest index (the first of equals), else none (air).
    fn winning(&self) -> Option<&Entry> {
        let entries = &self.entries[..self.len as usize];
        if let Some(e) = entries.iter().rev().find(|e| e.relative) {
            return Some(e);
        }
        entries
            .iter()
            .fold(None, |best: Option<&Entry>, e| match best {
                Some(b) if b.ior >= e.ior => Some(b),
                _ => Some(e),
            })
    }

    /// Returns the index of the medium the ray is in.
    pub fn ior(&self) -> f32 {
        self.winning().map_or(1.0, |e| e.ior)
    }

    /// Returns the material id of the solid whose medium the ray is in, or `None` in air.
    pub fn winner(&self) -> Option<u32> {
        self.winning().map(|e| e.id)
    }

    /// Returns true when the stack holds material `id`.
    pub fn contains(&self, id: u32) -> bool {
        self.entries[..self.len as usize].iter().any(|e| e.id == id)
    }

    /// Returns the crossing of the boundary of a solid of material `id` and index `ior` (below
    /// 1: relative to the medium the ray is in as it enters); `entering` says whether the ray
    /// goes into the solid (against its outward normal).
    pub fn cross(&self, id: u32, ior: f32, entering: bool) -> Crossing {
        let mut after = *self;
        if entering {
            if (after.len as usize) < DEPTH && !after.contains(id) {
                let relative = ior < 1.0;
                let ior = if relative { self.ior() * ior } else { ior };
                after.entries[after.len as usize] = Entry { id, ior, relative };
                after.len += 1;
            }
        } else if let Some(k) = after.entries[..after.len as usize]
            .iter()
            .position(|e| e.id == id)
        {
            after.entries.copy_within(k + 1..after.len as usize, k);
            after.len -= 1;
            after.entries[after.len as usize] = Entry::default();
        }
        Crossing {
            n_from: self.ior(),
            n_to: after.ior(),
            after,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const WATER: (u32, f32) = (1, 1.33);
    const GLASS: (u32, f32) = (2, 1.5);

    #[test]
    fn glass_ball_under_water() {
        let air = MediumStack::air();
        let c = air.cross(WATER.0, WATER.1, true);
        assert_eq!((c.n_from, c.n_to), (1.0, 1.33));
        let c2 = c.after.cross(GLASS.0, GLASS.1, true);
        assert_eq!(
            (c2.n_from, c2.n_to),
            (1.33, 1.5),
            "water to glass uses the ratio of both media"
        );
        let c3 = c2.after.cross(GLASS.0, GLASS.1, false);
        assert_eq!((c3.n_from, c3.n_to), (1.5, 1.33));
        let c4 = c3.after.cross(WATER.0, WATER.1, false);
        assert_eq!((c4.n_from, c4.n_to, c4.after), (1.33, 1.0, air));
    }

    #[test]
    fn ball_through_the_water_surface() {
        // Air → water → glass, then the water surface inside the ball is a false interface, and
        // leaving the ball above the water goes into air.
        let s = MediumStack::air()
            .cross(WATER.0, WATER.1, true)
            .after
            .cross(GLASS.0, GLASS.1, true)
            .after;
        let inside = s.cross(WATER.0, WATER.1, false);
        assert!(inside.is_false());
        let out = inside.after.cross(GLASS.0, GLASS.1, false);
        assert_eq!((out.n_from, out.n_to), (1.5, 1.0));
        // From air into the ball's top, across the water plane inside it, out of its bottom into water.
        let s = MediumStack::air().cross(GLASS.0, GLASS.1, true).after;
        let plane = s.cross(WATER.0, WATER.1, true);
        assert!(plane.is_false());
        let out = plane.after.cross(GLASS.0, GLASS.1, false);
        assert_eq!((out.n_from, out.n_to), (1.5, 1.33));
    }
}
