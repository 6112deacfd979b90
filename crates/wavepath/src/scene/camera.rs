use crate::geometry::Ray;
use glam::{Mat3, Vec3};

/// A pinhole (or thin-lens) camera with the CS184 conventions: the image plane sits at
/// z = -1 in camera space, spans 2 tan(hfov/2) by 2 tan(vfov/2), rays are clipped to
/// [nclip, fclip], and image coordinates (0,0) are the bottom-left corner.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    pub position: Vec3,
    /// Camera-to-world rotation; columns are the camera's right, up and backward (+Z) axes.
    pub c2w: Mat3,
    pub hfov_deg: f32,
    pub vfov_deg: f32,
    pub nclip: f32,
    pub fclip: f32,
    /// Thin-lens aperture radius; 0 is a pinhole.
    pub lens_radius: f32,
    pub focal_distance: f32,
    /// How the fields of view follow the image size ([`fit_to`](Self::fit_to)).
    pub fit: FovFit,
    /// Parallel projection (a COLLADA `<orthographic>` camera): rays leave the image plane
    /// along the view direction, and the plane's half extents are tan(hfov / 2) and
    /// tan(vfov / 2) world units, so that fitting to an image works as for angles.
    pub orthographic: bool,
}

/// The rule that turns a camera's field of view into the one of a `W x H` image. Formats
/// disagree here, and a picture matches its source only with the source's rule.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum FovFit {
    /// The vertical field stays, the horizontal one follows the aspect (glTF's `yfov`).
    Vertical,
    /// The horizontal field stays (a COLLADA `xfov` taken as the file's own camera).
    Horizontal,
    /// The field given spans the shorter side of the image, so a framing made for it holds
    /// in landscape and portrait pictures alike (the automatic camera).
    ShorterSide,
    /// The CS184 reference renderer: it fits the field once to its 800x600 start-up window
    /// and keeps the angle per pixel, so `W x H` is the centre window of that picture (wider
    /// beyond 800x600). `tan_half_600` is the tangent of half the vertical field at 600 rows.
    Cs184 { tan_half_600: f32 },
    /// Both fields as written, whatever the image size (a `-c` camera settings file, as the
    /// reference uses it).
    AsWritten,
}

impl FovFit {
    /// The CS184 rule for a file's optics: whichever of its angles is too narrow for the
    /// 4:3 start-up window is widened, `t = max(tan(vfov/2), 0.75 tan(hfov/2))`.
    /// ([`crate::cs184::fov_fit_tan_half_600`]).
    pub fn cs184(hfov_deg: f32, vfov_deg: f32) -> FovFit {
        FovFit::Cs184 { tan_half_600: crate::cs184::fov_fit_tan_half_600(hfov_deg, vfov_deg) }
    }
}

/// How a CS184 camera's field of view follows the image size: the caller's choice (`--fov`),
/// where [`FovFit`] is the camera's own rule. Cameras of other rules are not changed by it.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum FovRule {
    /// The reference renderer's rule: its 800x600 picture's angle per pixel, so `W x H`
    /// shows the centre `W x H` window of that picture (more than it beyond 800x600).
    #[default]
    Cs184,
    /// The whole 800x600 picture at any resolution (its vertical field kept): small renders
    /// show what the reference's picture shows.
    Frame,
}

crate::choice::named!(FovRule, "fov", {
    Cs184 => "cs184", "the reference renderer's rule: -r W H shows the centre W x H window of its 800x600 picture";
    Frame => "frame", "the whole 800x600 picture at any resolution (its vertical field kept)";
});

impl Default for Camera {
    fn default() -> Self {
        Camera::look_at(Vec3::new(0.0, 0.0, 3.0), Vec3::ZERO, Vec3::Y, 45.0, 4.0 / 3.0)
    }
}

impl Camera {
    /// A camera at `eye` looking at `target` with vertical field of view `vfov_deg`.
    pub fn look_at(eye: Vec3, target: Vec3, up: Vec3, vfov_deg: f32, aspect: f32) -> Self {
        let back = (eye - target).try_normalize().unwrap_or(Vec3::Z);
        let up_hint = if up.cross(back).length_squared() < 1e-12 { any_perpendicular(back) } else { up };
        let right = up_hint.cross(back).normalize();
        let true_up = back.cross(right).normalize();
        let mut cam = Camera {
            position: eye,
            c2w: Mat3::from_cols(right, true_up, back),
            hfov_deg: vfov_deg,
            vfov_deg,
            nclip: 0.01,
            fclip: 1e30,
            lens_radius: 0.0,
            focal_distance: CS184_FOCAL_DISTANCE,
            fit: FovFit::Vertical,
            orthographic: false,
        };
        cam.fit_to(aspect, 1.0);
        cam
    }

    /// Sets both fields of view for a `width x height` image by the camera's [`FovFit`].
    /// Only the ratio matters, except for the CS184 rule, which counts pixels.
    pub fn fit_to(&mut self, width: f32, height: f32) {
        let half_tan = |deg: f32| (deg.to_radians() * 0.5).tan();
        let from_tan = |t: f32| 2.0 * t.atan().to_degrees();
        let aspect = width / height;
        match self.fit {
            FovFit::Vertical => self.hfov_deg = from_tan(half_tan(self.vfov_deg) * aspect),
            FovFit::Horizontal => self.vfov_deg = from_tan(half_tan(self.hfov_deg) / aspect),
            FovFit::ShorterSide => {
                // The field is stored in vfov_deg until the first fit tells the sides apart.
                let t = half_tan(self.vfov_deg.min(self.hfov_deg));
                let (th, tv) = if aspect >= 1.0 { (t * aspect, t) } else { (t, t / aspect) };
                (self.hfov_deg, self.vfov_deg) = (from_tan(th), from_tan(tv));
            }
            FovFit::Cs184 { tan_half_600: t } => {
                self.hfov_deg = from_tan(width * t / 600.0);
                self.vfov_deg = from_tan(height * t / 600.0);
            }
            FovFit::AsWritten => {}
        }
    }

    /// Fits the camera to an image of this aspect (width / height) showing its whole frame:
    /// [`whole_frame`](Self::whole_frame), then [`fit_to`](Self::fit_to). For small renders
    /// of CS184 scenes that should show what the 800x600 picture shows.
    pub fn fit_aspect(&mut self, aspect: f32) {
        self.whole_frame();
        self.fit_to(aspect, 1.0);
    }

    /// This camera as a `width x height` image under `rule` sees through it. A copy, so that
    /// the scene keeps the file's camera and its rule: a render at another size (the
    /// viewer's resized window, a second render of one scene) fits from what the file said,
    /// not from an earlier fit.
    pub fn fitted(&self, rule: FovRule, width: usize, height: usize) -> Camera {
        let mut cam = *self;
        if rule == FovRule::Frame {
            cam.whole_frame();
        }
        cam.fit_to(width as f32, height as f32);
        cam
    }

    /// The CS184 rule turned into "the whole 800x600 picture at any size": the vertical
    /// field of the 800x600 picture, kept at every resolution (`--fov frame`). Other rules
    /// are left as they are.
    pub fn whole_frame(&mut self) {
        if let FovFit::Cs184 { tan_half_600 } = self.fit {
            self.vfov_deg = 2.0 * tan_half_600.atan().to_degrees();
            self.fit = FovFit::Vertical;
        }
    }

    /// A camera for a file that carries none: it sees a large face of the bounds at three
    /// quarters ([`three_quarter_view`]), the bounding sphere filling 95% of a 40-degree
    /// field across the shorter image side, clip planes around the sphere and the focus on
    /// its centre. Anywhere, at any scale: all of it is relative to the bounds.
    pub fn framing(lo: Vec3, hi: Vec3) -> Self {
        let center = 0.5 * (lo + hi);
        let radius = (0.5 * (hi - lo).length()).max(1e-6 * center.abs().max_element()).max(f32::MIN_POSITIVE);
        let fov: f32 = 40.0;
        let dist = radius / (fov.to_radians() * 0.5).sin() * 1.05;
        let dir = three_quarter_view(hi - lo);
        let mut cam = Camera::look_at(center + dir * dist, center, Vec3::Y, fov, 1.0);
        cam.fit = FovFit::ShorterSide;
        cam.nclip = (dist - radius).max(dist * 1e-4) * 0.5;
        cam.fclip = (dist + radius) * 2.0;
        cam.focal_distance = dist;
        cam
    }

    /// The reference renderer's placement of a COLLADA camera (a CS184 rule:
    /// [`crate::cs184`] lists them all): keep only the direction
    /// `view_hint` (from the target toward the camera), put the camera at
    /// `c + 1.5 |diag| view_hint` looking at the bounding-box centre `c`, with +Y up.
    pub fn cs184_place(&mut self, view_hint: Vec3, lo: Vec3, hi: Vec3) {
        let target = 0.5 * (lo + hi);
        let distance = 1.5 * (hi - lo).length();
        let dir = view_hint.try_normalize().unwrap_or(Vec3::Z);
        // Spherical angles as the reference computes them (phi from +Y, theta about Y).
        let mut phi = dir.y.clamp(-1.0, 1.0).acos();
        let theta = dir.x.atan2(dir.z);
        if phi.sin() == 0.0 {
            phi += 1e-6;
        }
        let sin_phi = phi.sin();
        let to_camera = distance * Vec3::new(sin_phi * theta.sin(), phi.cos(), sin_phi * theta.cos());
        let up = Vec3::new(0.0, if sin_phi > 0.0 { 1.0 } else { -1.0 }, 0.0);
        let right = up.cross(to_camera).normalize();
        let screen_up = to_camera.cross(right).normalize();
        self.position = target + to_camera;
        self.c2w = Mat3::from_cols(right, screen_up, to_camera.normalize());
    }

    /// Widens the clip range so that it covers the box `lo..hi` (the reference keeps the
    /// file's range after moving the camera, which can leave a whole scene beyond the far
    /// plane). Returns a line for the log when it changed anything.
    pub fn cover_bounds(&mut self, lo: Vec3, hi: Vec3) -> Option<String> {
        let (near, far) = distance_range(self.position, lo, hi);
        let (old_n, old_f) = (self.nclip, self.fclip);
        if far >= self.fclip {
            self.fclip = far * 1.01 + f32::EPSILON * self.position.abs().max_element();
        }
        if near > 0.0 && near <= self.nclip {
            self.nclip = near * 0.5;
        }
        ((old_n, old_f) != (self.nclip, self.fclip)).then(|| {
            format!(
                "the camera's clip range [{old_n}, {old_f}] does not cover the scene seen from where it was placed \
                 (distances {near} to {far}); widened to [{}, {}]",
                self.nclip, self.fclip
            )
        })
    }

    /// Direction (not normalised) through the image point `(x, y)` in [0,1]^2, bottom-left origin.
    #[inline]
    pub fn direction_camera_space(&self, x: f32, y: f32) -> Vec3 {
        let w = (self.hfov_deg.to_radians() * 0.5).tan();
        let h = (self.vfov_deg.to_radians() * 0.5).tan();
        Vec3::new((x - 0.5) * 2.0 * w, (y - 0.5) * 2.0 * h, -1.0)
    }

    /// The pinhole ray through `(x, y)` in [0,1]^2: unit direction, clipped to [nclip, fclip]
    /// (for an orthographic camera, the parallel ray from that point of the image plane).
    #[inline]
    pub fn generate_ray(&self, x: f32, y: f32) -> Ray {
        let d = self.direction_camera_space(x, y);
        if self.orthographic {
            let origin = self.position + self.c2w * Vec3::new(d.x, d.y, 0.0);
            return Ray { origin, dir: self.c2w * -Vec3::Z, tmin: self.nclip, tmax: self.fclip };
        }
        Ray { origin: self.position, dir: (self.c2w * d).normalize(), tmin: self.nclip, tmax: self.fclip }
    }

    /// Thin-lens ray: `lens` is a point on the unit disk (already mapped), scaled by the
    /// lens radius; the ray passes through the point where the pinhole ray meets the plane
    /// of focus.
    pub fn generate_lens_ray(&self, x: f32, y: f32, lens: glam::Vec2) -> Ray {
        // A parallel projection has no lens to defocus through.
        if self.lens_radius <= 0.0 || self.orthographic {
            return self.generate_ray(x, y);
        }
        let d_cam = self.direction_camera_space(x, y);
        let focus = d_cam * (self.focal_distance / -d_cam.z);
        let p_lens = Vec3::new(lens.x * self.lens_radius, lens.y * self.lens_radius, 0.0);
        let dir_cam = (focus - p_lens).normalize();
        // Clip distances are along the camera axis, so scale them by 1/|cos| like the pinhole ray.
        let dir = self.c2w * dir_cam;
        Ray { origin: self.position + self.c2w * p_lens, dir, tmin: self.nclip, tmax: self.fclip }
    }

    pub fn validate(&self) -> Result<(), String> {
        let ok = self.position.is_finite()
            && self.c2w.is_finite()
            && self.hfov_deg.is_finite()
            && self.vfov_deg.is_finite()
            && self.nclip.is_finite()
            && !self.fclip.is_nan();
        if !ok {
            return Err("camera has non-finite parameters".into());
        }
        if !(self.vfov_deg > 0.0 && self.vfov_deg < 180.0 && self.hfov_deg > 0.0 && self.hfov_deg < 180.0) {
            return Err(format!(
                "camera field of view {}x{} degrees is outside (0, 180)",
                self.hfov_deg, self.vfov_deg
            ));
        }
        if self.nclip < 0.0 || self.fclip <= self.nclip {
            return Err(format!("camera clip range [{}, {}] is empty", self.nclip, self.fclip));
        }
        Ok(())
    }
}

/// The reference renderer's default focal distance of the thin lens
/// ([`crate::cs184::FOCAL_DISTANCE`]).
pub const CS184_FOCAL_DISTANCE: f32 = crate::cs184::FOCAL_DISTANCE;

/// The direction from a box's centre toward the camera that sees a large face of the box at
/// three quarters. A face at least half as large as the largest counts as large; among those
/// the front (+Z) is preferred, then the side (+X), then the top (+Y), since Y-up models face
/// +Z. The view is 30 degrees to the side of the face's normal and 20 degrees above it (50
/// degrees above the top face, which is seen from above).
fn three_quarter_view(extent: Vec3) -> Vec3 {
    let area = Vec3::new(extent.y * extent.z, extent.x * extent.z, extent.x * extent.y);
    let large = |a: f32| a >= 0.5 * area.max_element();
    let (az, el) = (30f32.to_radians(), 20f32.to_radians());
    let d = if large(area.z) {
        Vec3::new(az.sin() * el.cos(), el.sin(), az.cos() * el.cos())
    } else if large(area.x) {
        Vec3::new(az.cos() * el.cos(), el.sin(), az.sin() * el.cos())
    } else {
        let el = 50f32.to_radians();
        Vec3::new(az.sin() * el.cos(), el.sin(), az.cos() * el.cos())
    };
    d.normalize()
}

/// The nearest and farthest distance from `p` to the box `lo..hi` (0 when inside).
fn distance_range(p: Vec3, lo: Vec3, hi: Vec3) -> (f32, f32) {
    let nearest = p.clamp(lo, hi);
    let farthest = Vec3::select(p.cmplt(0.5 * (lo + hi)), hi, lo);
    ((nearest - p).length(), (farthest - p).length())
}

fn any_perpendicular(v: Vec3) -> Vec3 {
    if v.x.abs() < 0.9 { Vec3::X.cross(v).normalize() } else { Vec3::Y.cross(v).normalize() }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn image_plane_follows_cs184_conventions() {
        let cam = Camera::look_at(Vec3::new(0.0, 0.0, 5.0), Vec3::ZERO, Vec3::Y, 60.0, 2.0);
        // Centre looks at the target.
        let c = cam.generate_ray(0.5, 0.5);
        assert!((c.dir - Vec3::NEG_Z).length() < 1e-6);
        // (0,0) is bottom-left: left is -X, bottom is -Y for this camera.
        let bl = cam.generate_ray(0.0, 0.0);
        assert!(bl.dir.x < 0.0 && bl.dir.y < 0.0);
        // The top edge is vfov/2 above the axis; the right edge hfov/2 to the side.
        let top = cam.generate_ray(0.5, 1.0).dir;
        assert!((top.y.atan2(-top.z).to_degrees() - 30.0).abs() < 1e-3);
        let right = cam.generate_ray(1.0, 0.5).dir;
        let half_h = right.x.atan2(-right.z).to_degrees();
        // tan(h/2) = aspect * tan(v/2).
        assert!((half_h.to_radians().tan() - 2.0 * 30f32.to_radians().tan()).abs() < 1e-4);
        assert_eq!((c.tmin, c.tmax), (cam.nclip, cam.fclip));
    }

    #[test]
    fn cs184_placement_frames_the_box_from_the_hint_direction() {
        let mut cam = Camera::default();
        let (lo, hi) = (Vec3::new(-1.0, 0.0, -1.0), Vec3::new(1.0, 1.5, 1.0));
        cam.cs184_place(Vec3::new(0.0, 0.0, 1.0), lo, hi);
        let centre = 0.5 * (lo + hi);
        let diag = (hi - lo).length();
        assert!((cam.position - (centre + Vec3::Z * 1.5 * diag)).length() < 1e-5);
        assert!((cam.generate_ray(0.5, 0.5).dir - Vec3::NEG_Z).length() < 1e-6);
        assert!((cam.c2w.y_axis - Vec3::Y).length() < 1e-6);
        // Looking straight down the axis does not produce NaN.
        cam.cs184_place(Vec3::Y, lo, hi);
        assert!(cam.c2w.is_finite() && cam.position.is_finite());
    }

    #[test]
    fn thin_lens_rays_meet_on_the_focal_plane() {
        let mut cam = Camera::look_at(Vec3::ZERO, Vec3::NEG_Z, Vec3::Y, 40.0, 1.0);
        cam.lens_radius = 0.2;
        cam.focal_distance = 3.0;
        let pin = cam.generate_ray(0.3, 0.7);
        let focus = pin.at(3.0 / -pin.dir.z);
        for lens in [glam::Vec2::new(1.0, 0.0), glam::Vec2::new(-0.5, 0.5), glam::Vec2::new(0.0, -1.0)] {
            let r = cam.generate_lens_ray(0.3, 0.7, lens);
            let p = r.at((focus.z - r.origin.z) / r.dir.z);
            assert!((p - focus).length() < 1e-5, "{p:?} vs {focus:?}");
        }
    }
}
