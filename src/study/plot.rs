//! The study's picture: error against seconds on log–log axes, one curve per setting.
//!
//! Text is drawn with a font shipped in the repository (DejaVu Sans, assets/fonts), so the
//! plot builds and renders on a machine without fontconfig or any system font.

use super::StudyResult;
use anyhow::{Context, Result};
use plotters::coord::Shift;
use plotters::prelude::*;
use std::path::Path;

static FONT: &[u8] = include_bytes!("../../assets/fonts/DejaVuSans.ttf");
/// Pixel size of the plot.
pub const SIZE: (u32, u32) = (900, 600);

/// Writes the plot as PNG and SVG (same content).
pub fn write_plots(result: &StudyResult, title: &str, png: &Path, svg: &Path) -> Result<()> {
    plotters::style::register_font("sans-serif", FontStyle::Normal, FONT)
        .map_err(|_| anyhow::anyhow!("the bundled font cannot be read"))?;
    {
        let root = SVGBackend::new(svg, SIZE).into_drawing_area();
        draw(&root, result, title).with_context(|| format!("{}: cannot draw plot", svg.display()))?;
        root.present().map_err(|e| anyhow::anyhow!("{}: cannot write plot: {e}", svg.display()))?;
    }
    let mut buf = vec![0u8; (SIZE.0 * SIZE.1 * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut buf, SIZE).into_drawing_area();
        draw(&root, result, title).with_context(|| format!("{}: cannot draw plot", png.display()))?;
        root.present().map_err(|e| anyhow::anyhow!("{}: cannot draw plot: {e}", png.display()))?;
    }
    let img = image::RgbImage::from_raw(SIZE.0, SIZE.1, buf).context("plot buffer size")?;
    img.save_with_format(png, image::ImageFormat::Png)
        .with_context(|| format!("{}: cannot write plot", png.display()))?;
    Ok(())
}

fn draw<DB: DrawingBackend>(root: &DrawingArea<DB, Shift>, result: &StudyResult, title: &str) -> Result<()>
where
    DB::ErrorType: 'static,
{
    let err = |e: DrawingAreaErrorKind<DB::ErrorType>| anyhow::anyhow!("{e}");
    root.fill(&WHITE).map_err(err)?;
    let pts: Vec<(f64, f64)> =
        result.points.iter().map(|p| (p.seconds, p.error.rmse)).filter(|&(t, e)| t > 0.0 && e > 0.0).collect();
    if pts.is_empty() {
        return Ok(());
    }
    let (mut x0, mut x1, mut y0, mut y1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
    for &(x, y) in &pts {
        x0 = x0.min(x);
        x1 = x1.max(x);
        y0 = y0.min(y);
        y1 = y1.max(y);
    }
    let (x0, x1, y0, y1) = (x0 / 1.5, x1 * 1.5, y0 / 1.5, y1 * 1.5);
    let mut chart = ChartBuilder::on(root)
        .caption(title, ("sans-serif", 22))
        .margin(12)
        .x_label_area_size(45)
        .y_label_area_size(70)
        .build_cartesian_2d((x0..x1).log_scale(), (y0..y1).log_scale())
        .map_err(err)?;
    chart
        .configure_mesh()
        .x_labels(12)
        .y_labels(16)
        .x_desc(if result.sweep.needs_denoiser() {
            "render time (s), plus the denoising's for denoised images"
        } else {
            "render time (s)"
        })
        .y_desc("RMSE vs reference (linear RGB)")
        .x_label_formatter(&|v| tick(*v))
        .y_label_formatter(&|v| tick(*v))
        .label_style(("sans-serif", 14))
        .axis_desc_style(("sans-serif", 16))
        .draw()
        .map_err(err)?;
    // A guide of slope -1/2 (Monte Carlo: error ~ 1/sqrt(time)) through the first curve's start.
    if let Some(p) = result.points.first() {
        let (t, e) = (p.seconds.max(1e-9), p.error.rmse);
        let guide = [(t, e), (x1, e * (x1 / t).powf(-0.5))];
        chart
            .draw_series(LineSeries::new(guide, ShapeStyle::from(&RGBColor(170, 170, 170)).stroke_width(1)))
            .map_err(err)?
            .label("slope -1/2")
            .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], RGBColor(170, 170, 170)));
    }
    for (ci, c) in result.curves.iter().enumerate() {
        let color = Palette99::pick(ci).to_rgba();
        let series: Vec<(f64, f64)> =
            result.curve_points(ci).map(|p| (p.seconds, p.error.rmse)).filter(|&(t, e)| t > 0.0 && e > 0.0).collect();
        chart
            .draw_series(LineSeries::new(series.clone(), color.stroke_width(2)))
            .map_err(err)?
            .label(c.label.clone())
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], color.stroke_width(2)));
        chart.draw_series(series.into_iter().map(|p| Circle::new(p, 3, color.filled()))).map_err(err)?;
    }
    // What the sweep's errors mean when not a plain render's (the denoise sweep's bias): the
    // legend's last line, the legend in the lower left corner, where error-against-time
    // curves do not go (the denoised curve starts at the denoising's time, upper right).
    let note = result.sweep.note();
    if let Some(note) = note {
        chart
            .draw_series(std::iter::empty::<Circle<(f64, f64), i32>>())
            .map_err(err)?
            .label(note)
            .legend(|(x, y)| EmptyElement::at((x, y)));
    }
    chart
        .configure_series_labels()
        .position(if note.is_some() { SeriesLabelPosition::LowerLeft } else { SeriesLabelPosition::UpperRight })
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .label_font(("sans-serif", 14))
        .draw()
        .map_err(err)?;
    Ok(())
}

/// A tick label with two significant digits and no exponent for ordinary magnitudes.
fn tick(v: f64) -> String {
    if !(v.is_finite() && v > 0.0) {
        return format!("{v}");
    }
    let digits = (1 - v.log10().floor() as i32).max(0) as usize;
    if digits > 6 {
        return format!("{v:.1e}");
    }
    let s = format!("{v:.digits$}");
    if s.contains('.') { s.trim_end_matches('0').trim_end_matches('.').to_string() } else { s }
}

#[cfg(test)]
mod tests {
    #[test]
    fn tick_labels() {
        assert_eq!(super::tick(0.001), "0.001");
        assert_eq!(super::tick(0.25), "0.25");
        assert_eq!(super::tick(3.0), "3");
        assert_eq!(super::tick(20.0), "20");
    }
}
