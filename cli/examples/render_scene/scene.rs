//! The scene: what the rays can meet (a floor and two spheres), the sky,
//! and the camera with its ray differentials.

use glam::Vec3;

/// What a ray hit.
#[derive(Clone, Copy, PartialEq)]
pub(crate) enum Material {
    Sky,
    Floor,
    Foil,
    Hide,
}

#[derive(Clone, Copy)]
pub(crate) struct Hit {
    pub(crate) material: Material,
    pub(crate) t: f32,
    pub(crate) point: Vec3,
    pub(crate) normal: Vec3,
}

pub(crate) const FOIL: (Vec3, f32) = (Vec3::new(-1.15, 1.0, 3.0), 1.0);
pub(crate) const HIDE: (Vec3, f32) = (Vec3::new(1.2, 1.0, 2.6), 1.0);
pub(crate) const SUN: Vec3 = Vec3::new(-0.45, 0.8, -0.4);

/// What the rays can meet: the floor up to `far`, and the two spheres or
/// none.
#[derive(Clone, Copy)]
pub(crate) struct World {
    pub(crate) spheres: bool,
    pub(crate) far: f32,
}

pub(crate) fn sphere(origin: Vec3, dir: Vec3, (centre, radius): (Vec3, f32)) -> Option<f32> {
    let oc = origin - centre;
    let b = oc.dot(dir);
    let c = oc.length_squared() - radius * radius;
    let disc = b * b - c;
    if disc < 0.0 {
        return None;
    }
    let t = -b - disc.sqrt();
    (t > 1e-3).then_some(t)
}

impl World {
    pub(crate) fn trace(&self, origin: Vec3, dir: Vec3) -> Hit {
        let mut hit = Hit { material: Material::Sky, t: f32::INFINITY, point: Vec3::ZERO, normal: Vec3::Y };
        if dir.y < -1e-4 {
            let t = -origin.y / dir.y;
            if t > 1e-3 && t < self.far {
                hit = Hit { material: Material::Floor, t, point: origin + t * dir, normal: Vec3::Y };
            }
        }
        if self.spheres {
            for (shape, material) in [(FOIL, Material::Foil), (HIDE, Material::Hide)] {
                if let Some(t) = sphere(origin, dir, shape).filter(|&t| t < hit.t) {
                    let point = origin + t * dir;
                    hit = Hit { material, t, point, normal: (point - shape.0) / shape.1 };
                }
            }
        }
        hit
    }

    pub(crate) fn in_shadow(&self, point: Vec3) -> bool {
        let sun = SUN.normalize();
        self.spheres && (sphere(point, sun, FOIL).is_some() || sphere(point, sun, HIDE).is_some())
    }
}

pub(crate) fn sky(dir: Vec3) -> Vec3 {
    let t = dir.y.clamp(0.0, 1.0);
    Vec3::new(0.75, 0.82, 0.9).lerp(Vec3::new(0.3, 0.45, 0.75), t)
}

/// A pinhole camera.
#[derive(Clone, Copy)]
pub(crate) struct Camera {
    pub(crate) eye: Vec3,
    pub(crate) forward: Vec3,
    pub(crate) right: Vec3,
    pub(crate) up: Vec3,
    /// Half the vertical field of view's tangent.
    pub(crate) fov: f32,
    pub(crate) width: usize,
    pub(crate) height: usize,
}

impl Camera {
    pub(crate) fn looking(eye: Vec3, at: Vec3, width: usize, height: usize) -> Self {
        let forward = (at - eye).normalize();
        let right = forward.cross(Vec3::Y).normalize() * -1.0;
        let up = right.cross(forward) * -1.0;
        Camera { eye, forward, right, up, fov: 0.75, width, height }
    }

    /// The unnormalised ray direction through image position (x, y) in
    /// pixels: forward + u·right + v·up.
    pub(crate) fn ray(&self, x: f32, y: f32) -> Vec3 {
        let (w, h) = (self.width as f32, self.height as f32);
        let u = (2.0 * x / w - 1.0) * self.fov * w / h;
        let v = (1.0 - 2.0 * y / h) * self.fov;
        self.forward + u * self.right + v * self.up
    }

    /// The footprint's width on the surface a ray hits (ray differentials:
    /// how the hit moves on the surface's tangent plane for one pixel along
    /// x and along y).
    pub(crate) fn footprint(&self, ray: Vec3, hit: &Hit, width: Width) -> Footprint {
        if hit.material == Material::Sky {
            return Footprint::default();
        }
        // P = eye + s·D on the plane through the hit with the hit's normal;
        // ∂P/∂u = s·(R − (R·n)/(D·n)·D), and one pixel is du = 2·fov/height.
        let s = hit.t / ray.length();
        let n = hit.normal;
        let dn = ray.dot(n);
        let pixel = 2.0 * self.fov / self.height as f32;
        let along = |r: Vec3| s * (r - r.dot(n) / dn * ray) * pixel;
        let (dx, dy) = (along(self.right), along(self.up));
        let w = match width {
            Width::Area => dx.cross(dy).length().sqrt(),
            Width::Major => dx.length().max(dy.length()),
        };
        if w.is_finite() {
            Footprint { dx, dy, width: w }
        } else {
            Footprint::default()
        }
    }
}

/// The scene's camera, and the plane's: low over the floor, the horizon
/// across the middle of the frame.
pub(crate) fn views(width: usize, height: usize) -> [(&'static str, World, Camera); 2] {
    [
        (
            "scene",
            World { spheres: true, far: 60.0 },
            Camera::looking(Vec3::new(0.0, 1.45, -1.4), Vec3::new(0.0, 0.8, 2.8), width, height),
        ),
        (
            "plane",
            World { spheres: false, far: 400.0 },
            Camera::looking(Vec3::new(0.0, 0.9, 0.0), Vec3::new(0.0, 0.35, 6.0), width, height),
        ),
    ]
}

/// How a pixel's footprint becomes one width.
#[derive(Clone, Copy, PartialEq, Debug)]
pub(crate) enum Width {
    /// The side of the square with the footprint's area.
    Area,
    /// The footprint's longer axis.
    Major,
}

/// A pixel's footprint on the surface its ray hits (world units): how the
/// hit moves for one pixel along x and along y, and one width for it.
#[derive(Clone, Copy, Default)]
pub(crate) struct Footprint {
    pub(crate) dx: Vec3,
    pub(crate) dy: Vec3,
    pub(crate) width: f32,
}

impl Footprint {
    /// The footprint's extent along a unit direction of the surface: a
    /// straight edge across that direction is covered over this distance.
    pub(crate) fn across(&self, direction: Vec3) -> f32 {
        self.dx.dot(direction).abs() + self.dy.dot(direction).abs()
    }
}
