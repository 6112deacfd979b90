//! `wavepath merge PARTS... -f OUT`: adds part files back into one image.

use super::MergeArgs;
use super::render_cmd::{check_output_extension, rate_image_path, write_atomic};
use anyhow::Result;

pub fn run(a: &MergeArgs) -> Result<()> {
    check_output_extension(&a.output)?;
    let merged = wavepath_apps::parts::merge_files(&a.parts)?;
    let m = &merged.parts[0];
    let film = merged.acc.to_film();
    wavepath::write_image(&film, &a.output, a.tonemap)?;
    // As `wavepath -a`: the sample-rate image only for adaptive renders.
    if m.adaptive {
        let rate = wavepath::rate_film(film.width, film.height, &merged.acc.samples_taken(), m.spp);
        wavepath::write_rate_image(&rate, &rate_image_path(&a.output))?;
    }
    let stats = merged.stats_json();
    eprintln!(
        "[wavepath] Merged {} parts ({} split) of {} {}x{}: {} rays, slowest part {:.3} s render, {:.3} s wall",
        merged.parts.len(),
        m.part.split.name(),
        m.scene,
        m.width,
        m.height,
        stats["rays"]["total"],
        stats["render_s"].as_f64().unwrap_or(0.0),
        stats["wall_s"].as_f64().unwrap_or(0.0),
    );
    eprintln!("[wavepath] Wrote {}", a.output.display());
    if let Some(p) = &a.stats {
        write_atomic(p, serde_json::to_string_pretty(&stats)?.as_bytes())?;
    }
    Ok(())
}
