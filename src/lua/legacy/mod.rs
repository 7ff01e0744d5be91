//! The course's legacy API (before Fall 2015): how caustic reads it.
//!
//! Legacy scripts compose each node's calls by post-multiplication, `M ← M·T`, so
//! `n:translate(..); n:rotate(..)` rotates the geometry first (each call in the node's own
//! frame), where the modern starter pre-multiplies, `M ← T·M` (each call in the parent's frame,
//! in call order; `cs488_lua_api.md` §0). `--dialect legacy` reads scripts the legacy way;
//! [`Dialect::compose`] is the one place the order becomes a matrix.
//!
//! ```lua
//! cow = gr.mesh('cow', 'cow.obj')
//! cow:translate(0, 1, 0); cow:scale(2, 2, 2)  -- legacy: scaled, then moved up by 1
//! ```

use glam::DAffine3;

/// Which era of the course's API a script is written for; it decides how transforms compose.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Dialect {
    /// Fall 2015 onwards: each call pre-multiplies, `M ← T·M`, and acts in the parent's frame in
    /// call order.
    #[default]
    Modern,
    /// Before Fall 2015: each call post-multiplies, `M ← M·T`, and acts in the node's own frame,
    /// so the last call touches the geometry first.
    Legacy,
}

impl Dialect {
    /// Returns node matrix `m` with the transform `t` of one more call composed in.
    pub fn compose(self, m: DAffine3, t: DAffine3) -> DAffine3 {
        match self {
            Dialect::Modern => t * m,
            Dialect::Legacy => m * t,
        }
    }
}
