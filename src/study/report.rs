//! The study's files: a CSV of every render, the plot, the images at equal time and a
//! Markdown report that shows them.

use super::{Ladder, StudyResult};
use anyhow::{Context, Result};
use std::fmt::Write as _;
use std::path::Path;
use wavepath::{Tonemap, rate_film, write_image, write_rate_image};

/// The columns of `study.csv`. `seconds` is a denoised row's render and denoising together,
/// `denoise_seconds` the denoising alone (empty on other rows); `ci95_mean` and
/// `predicted_rmse` are empty where they do not exist (a denoised image); `note` says what a
/// row's error means when it is not a plain render's (the denoise sweep's bias).
pub const CSV_HEADER: &str = "sweep,curve,spp,light_samples,max_depth,rr,hemisphere,adaptive_tolerance,\
seconds,rays,mean_spp,rmse,rel_mse,ci95_mean,predicted_rmse,ref_floor,invalid_samples,denoise_seconds,note";

/// A measure in the CSV's notation; empty when it does not exist (NaN).
fn measure(v: f64) -> String {
    if v.is_nan() { String::new() } else { format!("{v:.6e}") }
}

/// A measure in the report's tables; "n/a" when it does not exist (NaN).
fn cell(v: f64) -> String {
    if v.is_nan() { "n/a".into() } else { format!("{v:.4e}") }
}

/// One line per measured image (a denoise sweep's render gives a raw and a denoised line).
pub fn csv(result: &StudyResult) -> String {
    let mut out = String::from(CSV_HEADER);
    out.push('\n');
    for p in &result.points {
        let s = &p.settings;
        let note = match (p.denoise_seconds, result.sweep.note()) {
            (Some(_), Some(note)) => format!("\"{note}\""),
            _ => String::new(),
        };
        let _ = writeln!(
            out,
            "{},\"{}\",{},{},{},{},{},{},{:.6},{},{:.3},{:.6e},{:.6e},{},{},{:.6e},{},{},{}",
            result.sweep.name(),
            result.curves[p.curve].label.replace('"', "'"),
            s.sampling.spp,
            s.sampling.light_samples,
            s.paths.max_depth,
            s.paths.roulette.continue_prob,
            s.paths.hemisphere,
            p.tolerance.map(|t| t.to_string()).unwrap_or_default(),
            p.seconds,
            p.rays,
            p.error.mean_spp,
            p.error.rmse,
            p.error.rel_mse,
            measure(p.error.ci95),
            measure(p.error.predicted_rmse),
            p.error.ref_floor,
            p.invalid_samples,
            p.denoise_seconds.map(|t| format!("{t:.6}")).unwrap_or_default(),
            note
        );
    }
    out
}

/// Writes study.csv, error_vs_time.{png,svg}, the images and report.md into `dir`.
pub fn write_all(result: &StudyResult, dir: &Path, scene_label: &str, command: &str) -> Result<()> {
    std::fs::create_dir_all(dir).with_context(|| format!("{}: cannot create folder", dir.display()))?;
    let write = |name: &str, text: &str| {
        let p = dir.join(name);
        std::fs::write(&p, text).with_context(|| format!("{}: cannot write", p.display()))
    };
    write("study.csv", &csv(result))?;
    let title = format!("{scene_label}: error vs time ({} sweep)", result.sweep.name());
    super::plot::write_plots(result, &title, &dir.join("error_vs_time.png"), &dir.join("error_vs_time.svg"))?;
    write_image(&result.reference.mean, &dir.join("reference.png"), Tonemap::Cs184)?;

    let (target, picks) = result.equal_time();
    let rs = &result.reference_settings;
    let mut md = String::new();
    let _ = writeln!(md, "# What accuracy costs in time: {scene_label}, {} sweep\n", result.sweep.name());
    let _ = writeln!(md, "Made by:\n\n```sh\n{command}\n```\n");
    let _ = writeln!(
        md,
        "Reference: {}x{}, {} spp, -l {} -m {} --rr {} ({}). Errors are over linear RGB; \
         relMSE = mean (x - r)^2 / (r^2 + 0.01); ci95 is the mean per-pixel 95% confidence \
         half-width the render computes from its own samples.\n",
        rs.image.width,
        rs.image.height,
        rs.sampling.spp,
        rs.sampling.light_samples,
        rs.paths.max_depth,
        rs.paths.roulette.continue_prob,
        if result.reference_info.cached {
            "from the cache".to_string()
        } else {
            format!("{:.1} s", result.reference_info.seconds)
        }
    );
    if let Some(note) = result.sweep.note() {
        let _ = writeln!(
            md,
            "**Note:** {note}. Both curves come from the same renders, which keep albedo and \
             normal for the denoiser (the raw curve's time includes keeping them); a denoised \
             point's time is its render's plus the denoising's (Open Image Denoise, prefiltered \
             albedo and normal, on its own threads). A denoised image is judged against the \
             converged raw reference, never a denoised one: its error holds the denoiser's bias \
             besides what noise is left, and no variance predicts it (its ci95 and predicted RMSE do not exist: n/a \
             here, empty in the CSV), and errors near the reference's own noise ({:.2e} RMSE) \
             are not resolved.\n",
            result.points.first().map(|p| p.error.ref_floor).unwrap_or(f64::NAN)
        );
    }
    let _ = writeln!(md, "![error vs time](error_vs_time.png)\n");
    if let Some(table) = denoise_table(result) {
        md.push_str(&table);
    }
    let _ = writeln!(md, "## Each setting at about {target:.3} s\n");
    let _ = writeln!(md, "| setting | spp | seconds | rays | RMSE | relMSE | ci95 | image |");
    let _ = writeln!(md, "|---|---|---|---|---|---|---|---|");
    let mut images = vec![("reference".to_string(), "reference.png".to_string())];
    for (ci, pick) in picks.iter().enumerate() {
        let Some(p) = pick else { continue };
        let c = &result.curves[ci];
        let name = format!("equal_time_{}.png", c.slug);
        write_image(&p.film, &dir.join(&name), Tonemap::Cs184)?;
        let spp = match p.tolerance {
            Some(t) => format!("T {t}: mean {:.1} of {}", p.error.mean_spp, p.settings.sampling.spp),
            None => p.settings.sampling.spp.to_string(),
        };
        let _ = writeln!(
            md,
            "| {} | {spp} | {:.3} | {} | {:.4e} | {:.4e} | {} | ![]({name}) |",
            c.label,
            p.seconds,
            p.rays,
            p.error.rmse,
            p.error.rel_mse,
            cell(p.error.ci95)
        );
        images.push((c.label.clone(), name));
        if matches!(c.ladder, Ladder::Tolerances(_)) {
            let rate = rate_film(p.film.width, p.film.height, &p.samples, p.settings.sampling.spp);
            write_rate_image(&rate, &dir.join("adaptive_rate.png"))?;
            images.push((
                format!("sample rate of {} (blue: few, red: all {})", c.label, p.settings.sampling.spp),
                "adaptive_rate.png".into(),
            ));
        }
    }
    let _ = writeln!(md, "\n## Images\n");
    for (label, name) in images {
        let _ = writeln!(md, "**{label}**\n\n![{label}]({name})\n");
    }
    let _ = writeln!(md, "All measurements: [study.csv](study.csv).");
    write("report.md", &md)
}

/// For a sweep with denoised curves, each render beside its denoised image: spp, times,
/// errors and their ratios (denoised / raw).
fn denoise_table(result: &StudyResult) -> Option<String> {
    let mut md = String::new();
    for (di, d) in result.curves.iter().enumerate() {
        let Ladder::Denoised { of } = d.ladder else { continue };
        let raw = &result.curves[of];
        let _ = writeln!(md, "## {} beside {}, at each spp\n", raw.label, d.label);
        let _ = writeln!(
            md,
            "| spp | render s | raw RMSE | raw relMSE | denoising s | denoised s | denoised RMSE (biased) | \
             denoised relMSE (biased) | RMSE ratio | relMSE ratio |"
        );
        let _ = writeln!(md, "|---|---|---|---|---|---|---|---|---|---|");
        for dp in result.curve_points(di) {
            let spp = dp.settings.sampling.spp;
            let Some(rp) = result.curve_points(of).find(|p| p.settings.sampling.spp == spp) else { continue };
            let (r, e) = (&rp.error, &dp.error);
            let _ = writeln!(
                md,
                "| {spp} | {:.3} | {:.4e} | {:.4e} | {:.3} | {:.3} | {:.4e} | {:.4e} | {:.2} | {:.2} |",
                rp.seconds,
                r.rmse,
                r.rel_mse,
                dp.denoise_seconds.unwrap_or(f64::NAN),
                dp.seconds,
                e.rmse,
                e.rel_mse,
                e.rmse / r.rmse,
                e.rel_mse / r.rel_mse
            );
        }
        md.push('\n');
    }
    (!md.is_empty()).then_some(md)
}
