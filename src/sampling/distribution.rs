//! Piecewise-constant distributions over [0,1) and [0,1)^2, for importance sampling an
//! image (environment maps): a sample lands in a cell with probability proportional to the
//! cell's weight and is uniform inside it, so the density is exactly weight / mean weight.

/// A 1D piecewise-constant density on [0,1) with `n` equal cells.
#[derive(Clone, Debug)]
pub struct Distribution1D {
    /// Cell weights (non-negative).
    func: Vec<f32>,
    /// cdf[i] = sum of func[..i] / total; cdf[n] = 1. Kept in f64 while built so that long
    /// rows of tiny weights do not lose cells to rounding.
    cdf: Vec<f32>,
    /// Sum of the weights divided by the cell count (the mean weight).
    integral: f32,
}

impl Distribution1D {
    /// From cell weights; negative or non-finite weights count as zero. All-zero weights
    /// give the uniform distribution (so a black row can still be sampled consistently).
    pub fn new(weights: &[f32]) -> Self {
        let n = weights.len().max(1);
        let func: Vec<f32> =
            (0..n).map(|i| weights.get(i).copied().filter(|w| w.is_finite() && *w > 0.0).unwrap_or(0.0)).collect();
        let total: f64 = func.iter().map(|&w| w as f64).sum();
        let mut cdf = Vec::with_capacity(n + 1);
        cdf.push(0.0);
        let mut acc = 0.0f64;
        for (i, &w) in func.iter().enumerate() {
            acc += if total > 0.0 { w as f64 / total } else { 1.0 / n as f64 };
            cdf.push(if i + 1 == n { 1.0 } else { acc as f32 });
        }
        Distribution1D { func, cdf, integral: (total / n as f64) as f32 }
    }

    pub fn len(&self) -> usize {
        self.func.len()
    }

    pub fn is_empty(&self) -> bool {
        self.func.is_empty()
    }

    /// Mean weight (the integral of the step function over [0,1)).
    pub fn integral(&self) -> f32 {
        self.integral
    }

    /// Maps a uniform `u` to (x in [0,1), its density, its cell).
    #[inline]
    pub fn sample(&self, u: f32) -> (f32, f32, usize) {
        let n = self.func.len();
        // Last i with cdf[i] <= u, among cells 0..n.
        let i = self.cdf[1..n].partition_point(|&c| c <= u);
        let (lo, hi) = (self.cdf[i], self.cdf[i + 1]);
        let t = if hi > lo { ((u - lo) / (hi - lo)).clamp(0.0, 1.0) } else { 0.5 };
        let x = ((i as f32 + t) / n as f32).min(1.0 - f32::EPSILON);
        (x, self.pdf_cell(i), i)
    }

    /// Density of cell `i` (constant inside it).
    #[inline]
    pub fn pdf_cell(&self, i: usize) -> f32 {
        (self.cdf[i + 1] - self.cdf[i]) * self.func.len() as f32
    }

    /// Cell containing x in [0,1].
    #[inline]
    pub fn cell(&self, x: f32) -> usize {
        ((x * self.func.len() as f32) as usize).min(self.func.len() - 1)
    }
}

/// A 2D piecewise-constant density on [0,1)^2 over a `width` x `height` grid: the marginal
/// over rows (v) and, per row, the conditional over columns (u).
#[derive(Clone, Debug)]
pub struct Distribution2D {
    rows: Vec<Distribution1D>,
    marginal: Distribution1D,
}

impl Distribution2D {
    /// `weights` is row-major, `width * height` long.
    pub fn new(weights: &[f32], width: usize, height: usize) -> Self {
        let (w, h) = (width.max(1), height.max(1));
        let rows: Vec<Distribution1D> =
            (0..h).map(|y| Distribution1D::new(weights.get(y * w..(y + 1) * w).unwrap_or(&[]))).collect();
        let marginal = Distribution1D::new(&rows.iter().map(|r| r.integral()).collect::<Vec<_>>());
        Distribution2D { rows, marginal }
    }

    /// Maps two uniforms to ((u, v) in [0,1)^2, density with respect to du dv).
    #[inline]
    pub fn sample(&self, u: [f32; 2]) -> ([f32; 2], f32) {
        let (v, pv, row) = self.marginal.sample(u[1]);
        let (x, pu, _) = self.rows[row].sample(u[0]);
        ([x, v], pv * pu)
    }

    /// Density at (u, v) with respect to du dv.
    #[inline]
    pub fn pdf(&self, uv: [f32; 2]) -> f32 {
        let row = self.marginal.cell(uv[1]);
        let r = &self.rows[row];
        self.marginal.pdf_cell(row) * r.pdf_cell(r.cell(uv[0]))
    }

    pub fn width(&self) -> usize {
        self.rows[0].len()
    }

    pub fn height(&self) -> usize {
        self.rows.len()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::Sampler;

    fn weights(w: usize, h: usize) -> Vec<f32> {
        // A peaky, uneven function with zero cells: a bright spot, a ramp and a black band.
        (0..w * h)
            .map(|i| {
                let (x, y) = (i % w, i / w);
                if y == 1 {
                    0.0
                } else if (x, y) == (5, 4) {
                    40.0
                } else {
                    0.1 + x as f32 * 0.3 + (y as f32).sqrt()
                }
            })
            .collect()
    }

    #[test]
    fn pdf_integrates_to_one_and_is_proportional_to_weights() {
        let (w, h) = (8, 6);
        let f = weights(w, h);
        let d = Distribution2D::new(&f, w, h);
        let total: f32 = f.iter().sum();
        let mut integral = 0.0f64;
        for y in 0..h {
            for x in 0..w {
                let p = d.pdf([(x as f32 + 0.5) / w as f32, (y as f32 + 0.5) / h as f32]);
                // Density = weight / mean weight.
                let expect = f[y * w + x] / (total / (w * h) as f32);
                assert!((p - expect).abs() < 1e-4 * expect.max(1.0), "cell {x},{y}: {p} vs {expect}");
                integral += p as f64 / (w * h) as f64;
            }
        }
        assert!((integral - 1.0).abs() < 1e-5, "{integral}");
    }

    /// Pearson chi-square of 200k samples binned by cell against the pdf (zero cells must
    /// get no samples at all).
    #[test]
    fn samples_follow_the_pdf_chi_square() {
        let (w, h) = (8, 6);
        let f = weights(w, h);
        let d = Distribution2D::new(&f, w, h);
        let n = 200_000;
        let mut counts = vec![0u32; w * h];
        let mut s = Sampler::for_sample(7, 0, 0);
        for _ in 0..n {
            let ([u, v], pdf) = d.sample([s.next_f32(), s.next_f32()]);
            assert!((0.0..1.0).contains(&u) && (0.0..1.0).contains(&v));
            assert!((pdf - d.pdf([u, v])).abs() < 1e-4 * pdf, "sample pdf {pdf} vs pdf() {}", d.pdf([u, v]));
            counts[(v * h as f32) as usize * w + (u * w as f32) as usize] += 1;
        }
        let mut chi2 = 0.0f64;
        let mut cells = 0;
        for (i, &c) in counts.iter().enumerate() {
            let (x, y) = (i % w, i / w);
            let p = d.pdf([(x as f32 + 0.5) / w as f32, (y as f32 + 0.5) / h as f32]) as f64 / (w * h) as f64;
            if p == 0.0 {
                assert_eq!(c, 0, "zero-weight cell {x},{y} was sampled");
                continue;
            }
            let e = p * n as f64;
            chi2 += (c as f64 - e).powi(2) / e;
            cells += 1;
        }
        assert_eq!(cells, 40);
        // 39 degrees of freedom: the 0.1% critical value is 72.1.
        assert!(chi2 < 72.1, "chi-square {chi2} over {cells} cells");
    }

    #[test]
    fn uniform_when_all_zero_and_inside_cells() {
        let d = Distribution1D::new(&[0.0, 0.0, 0.0, 0.0]);
        assert_eq!(d.pdf_cell(2), 1.0);
        let (x, p, i) = d.sample(0.6);
        assert_eq!(i, 2);
        assert!((x - 0.6).abs() < 1e-6 && p == 1.0);
        // A sample inside a cell is spread uniformly across it.
        let d = Distribution1D::new(&[1.0, 3.0]);
        let (x, p, i) = d.sample(0.625);
        assert_eq!(i, 1);
        assert!((x - 0.75).abs() < 1e-6 && (p - 1.5).abs() < 1e-6);
    }
}
