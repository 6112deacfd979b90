//! `<light>` elements placed by their node's matrix (already including the axis conversion).

use super::xml::{Doc, child, cs184_extra};
use crate::scene::Light;
use anyhow::Result;
use glam::{Mat4, Vec3};
use roxmltree::Node;

/// A light at the node whose world matrix (axis conversion included) is `w`.
///
/// Directions are transformed as directions (the reference renderer's translation leak
/// is not copied). The CS184 `<area>` extra overrides the common technique.
pub fn light(d: &Doc, node: Node, w: Mat4) -> Result<Light> {
    let position = w.transform_point3(Vec3::ZERO);
    let facing = |n: Node| -> Result<Vec3> {
        w.transform_vector3(-Vec3::Z)
            .try_normalize()
            .ok_or_else(|| d.err(n, "the node matrix collapses the light's -Z axis"))
    };
    if let Some(area) = cs184_extra(node).filter(|e| e.tag_name().name() == "area") {
        // The reference spans up x direction = local -X and local +Y, so dim_x x dim_y
        // is the emitting direction.
        return Ok(Light::Area {
            position,
            direction: facing(area)?,
            dim_x: w.transform_vector3(-Vec3::X),
            dim_y: w.transform_vector3(Vec3::Y),
            radiance: d.color(d.child(area, "color")?)?,
        });
    }
    let tc = d.child(node, "technique_common")?;
    let Some(kind) = tc.children().find(|c| c.is_element()) else {
        return Err(d.err(tc, "names no light type"));
    };
    let color = d.color(d.child(kind, "color")?)?;
    let scalar_or = |tag: &str, default: f32| -> Result<f32> { child(kind, tag).map_or(Ok(default), |c| d.float(c)) };
    Ok(match kind.tag_name().name() {
        "point" => Light::Point {
            position,
            intensity: color,
            attenuation: [
                scalar_or("constant_attenuation", 1.0)?,
                scalar_or("linear_attenuation", 0.0)?,
                scalar_or("quadratic_attenuation", 0.0)?,
            ],
        },
        "directional" => Light::Directional { direction: facing(kind)?, radiance: color },
        "ambient" => Light::Hemisphere { radiance: color },
        "spot" => Light::Spot {
            position,
            direction: facing(kind)?,
            intensity: color,
            // COLLADA's full cone angle in degrees (default 180) and its exponent.
            cone_angle: scalar_or("falloff_angle", 180.0)?,
            falloff_exponent: scalar_or("falloff_exponent", 0.0)?,
        },
        other => return Err(d.err(kind, format!("unknown light type <{other}>"))),
    })
}
