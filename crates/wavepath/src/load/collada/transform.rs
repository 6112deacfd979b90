//! Axis conversion and node transforms.

use super::xml::{Doc, path};
use anyhow::Result;
use glam::{Mat4, Vec3, Vec4};
use roxmltree::Node;

/// The global matrix G that takes the file's up axis to the renderer's +Y, as the CS184
/// reference does: Z_UP x' = -x, y' = z, z' = y; X_UP x' = y, y' = x, z' = -z; Y_UP identity.
/// All three are proper rotations, so cross products and windings survive.
pub fn up_axis_matrix(d: &Doc, root: Node) -> Result<Mat4> {
    let Some(node) = path(root, &["asset", "up_axis"]) else {
        return Ok(Mat4::IDENTITY); // COLLADA's default is Y_UP.
    };
    let axis = node.text().unwrap_or("").trim();
    Ok(match axis {
        "Y_UP" => Mat4::IDENTITY,
        "Z_UP" => Mat4::from_cols(Vec4::new(-1.0, 0.0, 0.0, 0.0), Vec4::Z, Vec4::Y, Vec4::W),
        "X_UP" => Mat4::from_cols(Vec4::Y, Vec4::X, Vec4::new(0.0, 0.0, -1.0, 0.0), Vec4::W),
        other => return Err(d.err(node, format!("unknown up axis '{}' (expected X_UP, Y_UP or Z_UP)", other))),
    })
}

/// The node's local matrix: its transform elements composed in document order
/// (each one post-multiplied, as COLLADA specifies). A rotation about a zero-length axis
/// (some exporters write `0 0 0 angle`) turns nothing: it is skipped with a line in `notes`.
pub fn local_matrix(d: &Doc, node: Node, notes: &mut Vec<String>) -> Result<Mat4> {
    let mut m = Mat4::IDENTITY;
    for c in node.children().filter(|c| c.is_element()) {
        let t = match c.tag_name().name() {
            "matrix" => matrix(d, c)?,
            "translate" => Mat4::from_translation(Vec3::from_array(d.floats_n::<3>(c)?)),
            "scale" => Mat4::from_scale(Vec3::from_array(d.floats_n::<3>(c)?)),
            "rotate" => {
                let [x, y, z, deg] = d.floats_n::<4>(c)?;
                match Vec3::new(x, y, z).try_normalize() {
                    Some(axis) => Mat4::from_axis_angle(axis, deg.to_radians()),
                    None => {
                        notes.push(format!("warning: {}; skipped", d.err(c, "rotation axis has zero length")));
                        Mat4::IDENTITY
                    }
                }
            }
            "lookat" => {
                let v = d.floats_n::<9>(c)?;
                let eye = Vec3::new(v[0], v[1], v[2]);
                let target = Vec3::new(v[3], v[4], v[5]);
                let up = Vec3::new(v[6], v[7], v[8]);
                let frame = (target - eye).try_normalize().and_then(|f| Some((f, f.cross(up).try_normalize()?)));
                let Some((fwd, right)) = frame else {
                    return Err(d.err(c, "eye, interest and up do not define a frame"));
                };
                // View-to-world: the camera looks down its local -Z with +Y up.
                let true_up = right.cross(fwd);
                Mat4::from_cols(right.extend(0.0), true_up.extend(0.0), (-fwd).extend(0.0), eye.extend(1.0))
            }
            "skew" => return Err(d.err(c, "skew transforms are not supported")),
            _ => continue,
        };
        m *= t;
    }
    Ok(m)
}

/// A row-major `<matrix>` (or `<bind_shape_matrix>`). The affine part (the first 12
/// numbers) is required; a short last row is completed from (0 0 0 1), which nothing here
/// reads anyway. CS184's CBgems.dae has a camera matrix of 15 numbers, which the reference
/// renderer accepts.
pub fn matrix(d: &Doc, c: Node) -> Result<Mat4> {
    let v = d.floats(c, Some(17))?;
    if !(12..=16).contains(&v.len()) {
        return Err(
            d.err(c, format!("expected 16 numbers, found {}{}", v.len(), if v.len() > 16 { " or more" } else { "" }))
        );
    }
    let mut rows = Mat4::IDENTITY.transpose().to_cols_array();
    rows[..v.len()].copy_from_slice(&v);
    // Row-major in the file; glam is column-major.
    Ok(Mat4::from_cols_array(&rows).transpose())
}

/// The inverse transpose of the upper 3x3, for normals; `None` for a singular matrix.
pub fn normal_matrix(m: Mat4) -> Option<glam::Mat3> {
    let a = glam::Mat3::from_mat4(m);
    let det = a.determinant();
    (det.is_finite() && det.abs() > 1e-30).then(|| a.inverse().transpose())
}
