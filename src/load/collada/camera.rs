//! `<camera>`: the file's optics, and the two placements (`--camera cs184|file`).

use super::xml::{Doc, child, path};
use crate::load::CameraMode;
use crate::scene::{Camera, FovFit};
use anyhow::Result;
use glam::{Mat3, Mat4, Vec3, Vec4};
use roxmltree::Node;

/// Aspect assumed when the file gives only one field of view and no aspect ratio.
const DEFAULT_ASPECT: f32 = 4.0 / 3.0;

/// A camera's optics as the file gives them.
pub struct Optics {
    hfov_deg: f32,
    vfov_deg: f32,
    /// The file gives `xfov` (the horizontal angle is the one it means).
    has_xfov: bool,
    znear: f32,
    zfar: f32,
}

pub fn optics(d: &Doc, cam: Node) -> Result<Optics> {
    let persp = path(cam, &["optics", "technique_common", "perspective"]).ok_or_else(|| {
        if path(cam, &["optics", "technique_common", "orthographic"]).is_some() {
            d.err(cam, "orthographic cameras are not supported")
        } else {
            d.err(cam, "missing <optics><technique_common><perspective>")
        }
    })?;
    let get = |tag: &str| -> Result<Option<f32>> { child(persp, tag).map(|c| d.float(c)).transpose() };
    let (xfov, yfov, aspect) = (get("xfov")?, get("yfov")?, get("aspect_ratio")?);
    if let Some(a) = aspect
        && a <= 0.0
    {
        return Err(d.err(persp, format!("aspect_ratio {a} is not positive")));
    }
    let half_tan = |deg: f32| (deg.to_radians() * 0.5).tan();
    let from_tan = |t: f32| 2.0 * t.atan().to_degrees();
    let aspect = aspect.unwrap_or(DEFAULT_ASPECT);
    let (hfov_deg, vfov_deg) = match (xfov, yfov) {
        (Some(x), Some(y)) => (x, y),
        (Some(x), None) => (x, from_tan(half_tan(x) / aspect)),
        (None, Some(y)) => (from_tan(half_tan(y) * aspect), y),
        (None, None) => return Err(d.err(persp, "has neither <xfov> nor <yfov>")),
    };
    if !(hfov_deg > 0.0 && hfov_deg < 180.0 && vfov_deg > 0.0 && vfov_deg < 180.0) {
        return Err(d.err(persp, format!("field of view {hfov_deg} x {vfov_deg} degrees is outside (0, 180)")));
    }
    let znear = get("znear")?.unwrap_or(0.01);
    let zfar = get("zfar")?.unwrap_or(1e30);
    if znear < 0.0 || zfar <= znear {
        return Err(d.err(persp, format!("clip range znear={znear} zfar={zfar} is empty")));
    }
    Ok(Optics { hfov_deg, vfov_deg, has_xfov: xfov.is_some(), znear, zfar })
}

/// Places the camera. `w` is the camera node's world matrix with the axis conversion,
/// `bounds` the scene's (for the CS184 placement). Returns a line for the log when the
/// CS184 placement had to widen the file's clip range to see the scene.
pub fn place(o: &Optics, w: Mat4, mode: CameraMode, (lo, hi): (Vec3, Vec3)) -> (Camera, Option<String>) {
    let mut cam =
        Camera { hfov_deg: o.hfov_deg, vfov_deg: o.vfov_deg, nclip: o.znear, fclip: o.zfar, ..Camera::default() };
    let mut note = None;
    match mode {
        CameraMode::Cs184 => {
            // The reference's quirk: the point one unit in front of the camera, as a point.
            let d = (w * Vec4::new(0.0, 0.0, -1.0, 1.0)).truncate();
            cam.cs184_place(d.normalize_or_zero(), lo, hi);
            cam.fit = FovFit::cs184(o.hfov_deg, o.vfov_deg);
            // A camera already broken (bounds of 1e20 square to infinity) is refused by the
            // scene's validation: no note before that one-line error.
            if cam.validate().is_ok() {
                note = cam.cover_bounds(lo, hi);
            }
        }
        CameraMode::File => {
            cam.fit = if o.has_xfov { FovFit::Horizontal } else { FovFit::Vertical };
            cam.position = w.transform_point3(Vec3::ZERO);
            let axis = |v: Vec3, fallback: Vec3| w.transform_vector3(v).try_normalize().unwrap_or(fallback);
            cam.c2w = Mat3::from_cols(axis(Vec3::X, Vec3::X), axis(Vec3::Y, Vec3::Y), axis(Vec3::Z, Vec3::Z));
        }
    }
    (cam, note)
}
