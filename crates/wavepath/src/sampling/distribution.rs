//! Piecewise-constant distributions over [0,1) and [0,1)^2, for importance sampling an
//! image (environment maps): a sample lands in a cell with probability proportional to the
//! cell's weight and is uniform inside it, so the density is exactly weight / mean weight.

/// A 1D piecewise-constant density on [0,1) with `n` equal cells, sampled in constant time
/// with an alias table (Vose): one table entry, one cache line, per sample. A binary search
/// over a cdf takes ~log2(n) dependent loads, each a cache miss on a large map, which made
/// environment-map sampling memory-bound.
///
/// Each cell can carry a payload `P` (an environment map keeps its texel there), stored in
/// the alias slot beside the alias's payload, so that drawing a cell and reading what it
/// holds is a single cache line.
#[derive(Clone, Debug)]
pub struct Distribution1D<P: Copy = ()> {
    cells: Vec<AliasCell<P>>,
    /// Sum of the weights divided by the cell count (the mean weight).
    integral: f32,
}

/// One alias-table slot: stay in this cell with probability `stay`, else go to `alias`;
/// the densities of both cells are kept beside them so a sample touches one slot.
#[derive(Clone, Copy, Debug)]
struct AliasCell<P> {
    stay: f32,
    alias: u32,
    pdf: f32,
    alias_pdf: f32,
    payload: P,
    alias_payload: P,
}

impl Distribution1D {
    /// From cell weights; negative or non-finite weights count as zero. All-zero weights
    /// give the uniform distribution (so a black row can still be sampled consistently).
    pub fn new(weights: &[f32]) -> Self {
        Distribution1D::with_payload(weights, &vec![(); weights.len().max(1)])
    }
}

impl<P: Copy + Default> Distribution1D<P> {
    /// As [`new`](Distribution1D::new), cell `i` carrying `payload[i]` (missing: default).
    pub fn with_payload(weights: &[f32], payload: &[P]) -> Self {
        let n = weights.len().max(1);
        let pay = |i: usize| payload.get(i).copied().unwrap_or_default();
        let func: Vec<f64> = (0..n)
            .map(|i| weights.get(i).copied().filter(|w| w.is_finite() && *w > 0.0).unwrap_or(0.0) as f64)
            .collect();
        let total: f64 = func.iter().sum();
        // Cell probabilities scaled so that the mean is 1 (this is also the density).
        let scaled: Vec<f64> = func.iter().map(|&w| if total > 0.0 { w * n as f64 / total } else { 1.0 }).collect();
        let mut cells: Vec<AliasCell<P>> = scaled
            .iter()
            .enumerate()
            .map(|(i, &p)| AliasCell {
                stay: 1.0,
                alias: i as u32,
                pdf: p as f32,
                alias_pdf: p as f32,
                payload: pay(i),
                alias_payload: pay(i),
            })
            .collect();
        let mut left = scaled.clone();
        let (mut small, mut large): (Vec<usize>, Vec<usize>) = (0..n).partition(|&i| left[i] < 1.0);
        while let (Some(&s), Some(&l)) = (small.last(), large.last()) {
            small.pop();
            cells[s].stay = left[s] as f32;
            cells[s].alias = l as u32;
            cells[s].alias_pdf = scaled[l] as f32;
            cells[s].alias_payload = pay(l);
            left[l] -= 1.0 - left[s];
            if left[l] < 1.0 {
                large.pop();
                small.push(l);
            }
        }
        // What remains (either list, after rounding) stays in its own cell.
        for i in small.into_iter().chain(large) {
            cells[i].stay = 1.0;
            cells[i].alias = i as u32;
            cells[i].alias_pdf = cells[i].pdf;
            cells[i].alias_payload = cells[i].payload;
        }
        Distribution1D { cells, integral: (total / n as f64) as f32 }
    }

    /// Mean weight (the integral of the step function over [0,1)).
    pub fn integral(&self) -> f32 {
        self.integral
    }

    /// Maps a uniform `u` to (x in [0,1), its density, its cell); x is uniform inside the cell.
    #[inline]
    pub fn sample(&self, u: f32) -> (f32, f32, usize) {
        let (x, pdf, cell, _) = self.sample_payload(u);
        (x, pdf, cell)
    }

    /// As [`sample`](Self::sample), plus the cell's payload.
    #[inline]
    pub fn sample_payload(&self, u: f32) -> (f32, f32, usize, P) {
        let n = self.cells.len();
        let scaled = u.clamp(0.0, 1.0) * n as f32;
        let i = (scaled as usize).min(n - 1);
        let frac = (scaled - i as f32).clamp(0.0, 1.0);
        let c = self.cells[i];
        let (cell, pdf, t, p) = if frac < c.stay {
            (i, c.pdf, frac / c.stay, c.payload)
        } else {
            (c.alias as usize, c.alias_pdf, (frac - c.stay) / (1.0 - c.stay), c.alias_payload)
        };
        let x = ((cell as f32 + t.clamp(0.0, 1.0)) / n as f32).min(1.0 - f32::EPSILON);
        (x, pdf, cell, p)
    }

    /// Density of cell `i` (constant inside it).
    #[inline]
    pub fn pdf_cell(&self, i: usize) -> f32 {
        self.cells[i].pdf
    }

    /// Cell containing x in [0,1].
    #[cfg(test)]
    pub fn cell(&self, x: f32) -> usize {
        ((x * self.cells.len() as f32) as usize).min(self.cells.len() - 1)
    }
}

/// A 2D piecewise-constant density on [0,1)^2 over a `width` x `height` grid: the marginal
/// over rows (v) and, per row, the conditional over columns (u), as alias tables.
///
/// The rows' tables are one flat array of 8-byte slots (stay probability, alias column): a
/// draw reads the marginal (small, cached), one slot, then the cell's density, and a loop over
/// lanes can do each step for all of them. A 1200x600 environment map's slots take 5.8 MB,
/// where slots carrying both densities and both texels (40 bytes) took 29 MB and missed every
/// cache on each draw.
#[derive(Clone, Debug)]
pub struct Distribution2D {
    width: usize,
    marginal: Distribution1D,
    slots: Vec<Slot>,
    /// Each cell's density per du dv (the row's marginal times the column's conditional).
    pdf: Vec<f32>,
}

/// One row's alias-table slot: stay in this column with probability `stay`, else go to `alias`.
#[derive(Clone, Copy, Debug)]
struct Slot {
    stay: f32,
    alias: u32,
}

impl Distribution2D {
    /// `weights` is row-major, `width * height` long; negative or non-finite weights count as
    /// zero.
    pub fn new(weights: &[f32], width: usize, height: usize) -> Self {
        let (w, h) = (width.max(1), height.max(1));
        let rows: Vec<Distribution1D> =
            (0..h).map(|y| Distribution1D::new(weights.get(y * w..(y + 1) * w).unwrap_or(&[]))).collect();
        let marginal = Distribution1D::new(&rows.iter().map(|r| r.integral()).collect::<Vec<_>>());
        let slots = rows.iter().flat_map(|r| r.cells.iter().map(|c| Slot { stay: c.stay, alias: c.alias })).collect();
        let pdf = rows
            .iter()
            .enumerate()
            .flat_map(|(y, r)| r.cells.iter().map(move |c| (y, c.pdf)))
            .map(|(y, p)| marginal.pdf_cell(y) * p)
            .collect();
        Distribution2D { width: w, marginal, slots, pdf }
    }

    /// Maps two uniforms to ((u, v) in [0,1)^2, density with respect to du dv).
    #[cfg(test)]
    pub fn sample(&self, u: [f32; 2]) -> ([f32; 2], f32) {
        let (uv, cell) = self.draw(u);
        (uv, self.pdf[cell])
    }

    /// Maps two uniforms to (u, v) in [0,1)^2 and the index of its cell (`y * width + x`):
    /// the row from the marginal, then one slot of that row's table.
    #[inline(always)]
    pub fn draw(&self, u: [f32; 2]) -> ([f32; 2], usize) {
        let (v, _, row) = self.marginal.sample(u[1]);
        let n = self.width;
        let scaled = u[0].clamp(0.0, 1.0) * n as f32;
        let i = (scaled as usize).min(n - 1);
        let frac = (scaled - i as f32).clamp(0.0, 1.0);
        let slot = self.slots[row * n + i];
        let (column, t) = if frac < slot.stay {
            (i, frac / slot.stay)
        } else {
            (slot.alias as usize, (frac - slot.stay) / (1.0 - slot.stay))
        };
        let x = ((column as f32 + t.clamp(0.0, 1.0)) / n as f32).min(1.0 - f32::EPSILON);
        ([x, v], row * n + column)
    }

    /// Density in cell (x, y) with respect to du dv, as [`pdf`](Self::pdf) anywhere in it.
    pub fn pdf_of_cell(&self, x: usize, y: usize) -> f32 {
        self.pdf[y * self.width + x]
    }

    /// Density at (u, v) with respect to du dv.
    #[cfg(test)]
    pub fn pdf(&self, uv: [f32; 2]) -> f32 {
        let h = self.pdf.len() / self.width;
        let x = ((uv[0] * self.width as f32) as usize).min(self.width - 1);
        let y = ((uv[1] * h as f32) as usize).min(h - 1);
        self.pdf_of_cell(x, y)
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
        // Densities are weight / mean weight, and a sample lands in the cell it reports.
        let d = Distribution1D::new(&[1.0, 3.0]);
        assert_eq!((d.pdf_cell(0), d.pdf_cell(1)), (0.5, 1.5));
        for k in 0..100 {
            let (x, p, i) = d.sample(k as f32 / 100.0);
            assert_eq!(d.cell(x), i);
            assert_eq!(p, d.pdf_cell(i));
        }
    }
}
