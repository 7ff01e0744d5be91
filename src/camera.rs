//! The pinhole camera of `gr.render(…, eye, view, up, fov, …)`.
//!
//! `view` is a direction and `up` only approximately up: the basis is `w = normalize(view)`,
//! `u = normalize(w × up)`, `v = u × w`. `fov` is the vertical field of view in degrees. Pixel
//! `(x, y)` spans `[x, x+1) × [y, y+1)` with `y = 0` the top row, so its centre is `(x+½, y+½)`.

use crate::desc::CameraDesc;
use crate::geometry::Ray;
use glam::Vec3A;

/// A camera that turns image-plane positions into world-space rays.
#[derive(Clone, Copy, Debug)]
pub struct Camera {
    pub eye: Vec3A,
    /// Unit view direction.
    pub w: Vec3A,
    /// Unit right vector.
    pub u: Vec3A,
    /// Unit up vector, perpendicular to `w` and `u`.
    pub v: Vec3A,
    half_height: f32,
    half_width: f32,
    width: f32,
    height: f32,
}

impl Camera {
    /// Returns the camera for an image of `width × height` pixels (`up` must not be parallel to `view`).
    pub fn new(d: &CameraDesc, width: u32, height: u32) -> Camera {
        let w = Vec3A::from(d.view).normalize();
        let u = w.cross(d.up.into()).normalize();
        let v = u.cross(w);
        let half_height = (d.fov_deg.to_radians() * 0.5).tan();
        Camera {
            eye: d.eye.into(),
            w,
            u,
            v,
            half_height,
            half_width: half_height * width as f32 / height as f32,
            width: width as f32,
            height: height as f32,
        }
    }

    /// Returns the image's width and height in pixels.
    pub fn size(&self) -> (u32, u32) {
        (self.width as u32, self.height as u32)
    }

    /// Returns the primary ray through image-plane position `(x, y)` in pixel units (not normalised).
    pub fn ray(&self, x: f32, y: f32) -> Ray {
        let sx = (2.0 * x / self.width - 1.0) * self.half_width;
        let sy = (2.0 * y / self.height - 1.0) * self.half_height;
        Ray::new(self.eye, (self.w + sx * self.u - sy * self.v).normalize())
    }

    /// Returns the image-plane position (pixel units) where world point `p` appears, or `None`
    /// when `p` is behind the camera. The inverse of [`Camera::ray`].
    pub fn project(&self, p: Vec3A) -> Option<(f32, f32)> {
        let d = p - self.eye;
        let depth = d.dot(self.w);
        if depth <= 0.0 {
            return None;
        }
        let sx = d.dot(self.u) / depth;
        let sy = d.dot(self.v) / depth;
        let x = (sx / self.half_width + 1.0) * 0.5 * self.width;
        let y = (1.0 - sy / self.half_height) * 0.5 * self.height;
        Some((x, y))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    #[test]
    fn centre_corner_and_orthonormal_basis() {
        let d = CameraDesc {
            eye: Vec3::new(0.0, 0.0, 800.0),
            view: Vec3::new(0.0, 0.0, -800.0),
            up: Vec3::new(0.0, 1.0, 0.5),
            fov_deg: 90.0,
        };
        let cam = Camera::new(&d, 200, 100);
        assert!(cam.u.dot(cam.v).abs() < 1e-6 && cam.w.dot(cam.v).abs() < 1e-6);
        assert!((cam.u - Vec3A::X).length() < 1e-6, "u = {}", cam.u);
        let centre = cam.ray(100.0, 50.0);
        assert!((centre.dir - Vec3A::new(0.0, 0.0, -1.0)).length() < 1e-6);
        // Top-left corner: 45° up (fov 90) and tan = 2 to the left (aspect 2).
        let c = cam.ray(0.0, 0.0).dir;
        assert!(
            (c.x / -c.z + 2.0).abs() < 1e-5 && (c.y / -c.z - 1.0).abs() < 1e-5,
            "{c}"
        );
        // project() inverts ray().
        let (x, y) = cam
            .project(cam.eye + cam.ray(37.25, 81.5).dir * 10.0)
            .unwrap();
        assert!(
            (x - 37.25).abs() < 1e-3 && (y - 81.5).abs() < 1e-3,
            "({x}, {y})"
        );
        assert!(cam.project(cam.eye - cam.w).is_none());
    }
}
