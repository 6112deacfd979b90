//! The CS184 camera settings file (`-c FILE`): the text the reference renderer dumps.
//!
//! Lines: `hFov vFov ar nClip fClip`, `pos.xyz target.xyz`, `phi theta r minR maxR`,
//! `c2w` (9 numbers, row-major), optionally `screenW screenH screenDist` and
//! `focalDistance lensRadius`.
//!
//! Read as the reference renderer reads it: both fields of view as written (not re-fitted
//! to the image), the position and `c2w`; the screen size, screen distance, target and angles
//! do not affect the picture, and the lens values are not taken from the file (`-b`/`-d` or
//! their defaults replace them).

use super::{CS184_FOCAL_DISTANCE, Camera, FovFit};
use anyhow::{Context, Result, bail};
use glam::{Mat3, Vec3};
use std::path::Path;

pub fn read_camera_file(path: &Path) -> Result<Camera> {
    let shown = path.display();
    let text = std::fs::read_to_string(path).with_context(|| format!("{shown}: cannot read camera file"))?;
    parse_camera_settings(&text).map_err(|e| anyhow::anyhow!("{shown}: {e}"))
}

pub fn parse_camera_settings(text: &str) -> Result<Camera> {
    let nums: Vec<f32> = text
        .split_whitespace()
        .enumerate()
        .map(|(i, t)| t.parse::<f32>().map_err(|_| anyhow::anyhow!("value {} ('{t}') is not a number", i + 1)))
        .collect::<Result<_>>()?;
    if nums.len() < 25 {
        bail!(
            "camera file has {} numbers, expected at least 25 (fov, clip, position, target, angles, c2w)",
            nums.len()
        );
    }
    if let Some(i) = nums.iter().position(|v| !v.is_finite()) {
        bail!("value {} is not finite", i + 1);
    }
    let (hfov, vfov, nclip, fclip) = (nums[0], nums[1], nums[3], nums[4]);
    let position = Vec3::new(nums[5], nums[6], nums[7]);
    let m = &nums[16..25];
    // Row-major in the file; glam matrices are column-major.
    let c2w = Mat3::from_cols(Vec3::new(m[0], m[3], m[6]), Vec3::new(m[1], m[4], m[7]), Vec3::new(m[2], m[5], m[8]));
    let cam = Camera {
        position,
        c2w,
        hfov_deg: hfov,
        vfov_deg: vfov,
        nclip,
        fclip,
        lens_radius: 0.0,
        focal_distance: CS184_FOCAL_DISTANCE,
        fit: FovFit::AsWritten,
        orthographic: false,
    };
    cam.validate().map_err(|e| anyhow::anyhow!(e))?;
    Ok(cam)
}

/// Writes a camera in the same format (so a framing can be saved and reused with `-c`).
pub fn format_camera_settings(cam: &Camera, width: usize, height: usize) -> String {
    let target = cam.position - cam.c2w.z_axis;
    let m = cam.c2w.transpose().to_cols_array();
    let screen_dist = height as f32 / (2.0 * (cam.vfov_deg.to_radians() / 2.0).tan());
    let back = cam.c2w.z_axis;
    let phi = back.y.clamp(-1.0, 1.0).acos();
    let theta = back.x.atan2(back.z);
    format!(
        "{} {} {} {} {}\n{} {} {} {} {} {}\n{} {} 1 0 1e30\n{} {} {} {} {} {} {} {} {}\n{} {} {}\n{} {}\n",
        cam.hfov_deg,
        cam.vfov_deg,
        width as f32 / height as f32,
        cam.nclip,
        cam.fclip,
        cam.position.x,
        cam.position.y,
        cam.position.z,
        target.x,
        target.y,
        target.z,
        phi,
        theta,
        m[0],
        m[1],
        m[2],
        m[3],
        m[4],
        m[5],
        m[6],
        m[7],
        m[8],
        width,
        height,
        screen_dist,
        cam.focal_distance,
        cam.lens_radius
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trip() {
        let mut cam = Camera::look_at(Vec3::new(1.0, 2.0, 3.0), Vec3::ZERO, Vec3::Y, 35.0, 1.5);
        cam.lens_radius = 0.05;
        cam.focal_distance = 2.5;
        let back = parse_camera_settings(&format_camera_settings(&cam, 300, 200)).unwrap();
        assert!((back.position - cam.position).length() < 1e-5);
        assert!((back.c2w.z_axis - cam.c2w.z_axis).length() < 1e-5);
        assert!((back.hfov_deg - cam.hfov_deg).abs() < 1e-4);
        assert!((back.vfov_deg - cam.vfov_deg).abs() < 1e-4);
        // The lens is not the file's: -b/-d or the reference's defaults replace it.
        assert_eq!((back.lens_radius, back.focal_distance), (0.0, CS184_FOCAL_DISTANCE));
        assert_eq!(back.fit, FovFit::AsWritten);
    }

    #[test]
    fn rejects_short_and_garbage() {
        assert!(parse_camera_settings("1 2 3").is_err());
        assert!(parse_camera_settings(&"x ".repeat(30)).is_err());
        assert!(parse_camera_settings(&"nan ".repeat(30)).is_err());
    }
}
