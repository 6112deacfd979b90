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
    /// `<orthographic>`: the two angles encode the half extents xmag and ymag as their
    /// half-angle tangents ([`Camera::orthographic`]).
    orthographic: bool,
}

pub fn optics(d: &Doc, cam: Node) -> Result<Optics> {
    let technique = path(cam, &["optics", "technique_common"]);
    let (proj, orthographic) = match technique.and_then(|t| child(t, "perspective")) {
        Some(p) => (p, false),
        None => match technique.and_then(|t| child(t, "orthographic")) {
            Some(o) => (o, true),
            None => return Err(d.err(cam, "missing <optics><technique_common><perspective> or <orthographic>")),
        },
    };
    let get = |tag: &str| -> Result<Option<f32>> { child(proj, tag).map(|c| d.float(c)).transpose() };
    let (x_tag, y_tag) = if orthographic { ("xmag", "ymag") } else { ("xfov", "yfov") };
    let (x, y, aspect) = (get(x_tag)?, get(y_tag)?, get("aspect_ratio")?);
    if let Some(a) = aspect
        && a <= 0.0
    {
        return Err(d.err(proj, format!("aspect_ratio {a} is not positive")));
    }
    let aspect = aspect.unwrap_or(DEFAULT_ASPECT);
    // Both kinds as half-angle tangents: a field of view's, or a half extent itself.
    let to_tan = |v: f32| if orthographic { v } else { (v.to_radians() * 0.5).tan() };
    let (tx, ty) = match (x.map(to_tan), y.map(to_tan)) {
        (Some(x), Some(y)) => (x, y),
        (Some(x), None) => (x, x / aspect),
        (None, Some(y)) => (y * aspect, y),
        (None, None) => return Err(d.err(proj, format!("has neither <{x_tag}> nor <{y_tag}>"))),
    };
    let from_tan = |t: f32| 2.0 * t.atan().to_degrees();
    let (hfov_deg, vfov_deg) = (from_tan(tx), from_tan(ty));
    if !(hfov_deg > 0.0 && hfov_deg < 180.0 && vfov_deg > 0.0 && vfov_deg < 180.0) {
        let what = if orthographic {
            format!("view size {tx} x {ty} is not positive and finite")
        } else {
            format!("field of view {hfov_deg} x {vfov_deg} degrees is outside (0, 180)")
        };
        return Err(d.err(proj, what));
    }
    let znear = get("znear")?.unwrap_or(0.01);
    let zfar = get("zfar")?.unwrap_or(1e30);
    if znear < 0.0 || zfar <= znear {
        return Err(d.err(proj, format!("clip range znear={znear} zfar={zfar} is empty")));
    }
    Ok(Optics { hfov_deg, vfov_deg, has_xfov: x.is_some(), znear, zfar, orthographic })
}

/// Places the camera. `w` is the camera node's world matrix with the axis conversion,
/// `bounds` the scene's (for the CS184 placement). Returns a line for the log when the
/// CS184 placement had to widen the file's clip range to see the scene. An orthographic
/// camera is always placed as the file says: the reference renderer has none to imitate.
pub fn place(o: &Optics, w: Mat4, mode: CameraMode, (lo, hi): (Vec3, Vec3)) -> (Camera, Option<String>) {
    let mut cam = Camera {
        hfov_deg: o.hfov_deg,
        vfov_deg: o.vfov_deg,
        nclip: o.znear,
        fclip: o.zfar,
        orthographic: o.orthographic,
        ..Camera::default()
    };
    let mut note = None;
    let mode = if o.orthographic { CameraMode::File } else { mode };
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
