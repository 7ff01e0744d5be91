//! The film: a linear-RGB image (or a window of one) with the camera rays each pixel took. A leaf
//! that the render passes, `io` and the command line import downward.

pub mod log;

use glam::Vec3A;

/// A linear-RGB image, row 0 at the top: the whole image or a window (crop) of it.
#[derive(Clone, Debug, PartialEq)]
pub struct Film {
    pub width: u32,
    pub height: u32,
    /// Row-major pixels, `width × height` of them.
    pub pixels: Vec<Vec3A>,
    /// Camera rays traced for each pixel (same layout as `pixels`).
    pub samples: Vec<u32>,
    /// Where this window sits in the full image, and the full image's size.
    pub window: Window,
}

impl Film {
    /// Returns the pixel at column `x`, row `y` of this film (0 = top).
    pub fn get(&self, x: u32, y: u32) -> Vec3A {
        self.pixels[(y * self.width + x) as usize]
    }
}

/// Largest image caustic renders or stitches, in pixels (about 8k × 8k).
pub const MAX_PIXELS: u64 = 1 << 26;

/// A rectangle `[x0, x1) × [y0, y1)` of an image `full_width × full_height` pixels.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Window {
    pub x0: u32,
    pub y0: u32,
    pub x1: u32,
    pub y1: u32,
    pub full_width: u32,
    pub full_height: u32,
}

impl Window {
    /// Returns the window covering a whole `width × height` image.
    pub fn full(width: u32, height: u32) -> Window {
        Window {
            x0: 0,
            y0: 0,
            x1: width,
            y1: height,
            full_width: width,
            full_height: height,
        }
    }

    /// Returns the window's width and height.
    pub fn size(&self) -> (u32, u32) {
        (self.x1 - self.x0, self.y1 - self.y0)
    }

    /// Returns the window as `[x0, y0, x1, y1, full_width, full_height]`, the order its records
    /// in files keep (a PNG tile's text, a progressive pass file).
    pub fn to_array(&self) -> [u32; 6] {
        [
            self.x0,
            self.y0,
            self.x1,
            self.y1,
            self.full_width,
            self.full_height,
        ]
    }

    /// Returns the window [`Window::to_array`] gave `v` for (not checked: see
    /// [`Window::is_valid`]).
    pub fn from_array(v: [u32; 6]) -> Window {
        let [x0, y0, x1, y1, full_width, full_height] = v;
        Window {
            x0,
            y0,
            x1,
            y1,
            full_width,
            full_height,
        }
    }

    /// Returns true when the window is non-empty and inside the full image.
    pub fn is_valid(&self) -> bool {
        self.x0 < self.x1
            && self.y0 < self.y1
            && self.x1 <= self.full_width
            && self.y1 <= self.full_height
    }
}
