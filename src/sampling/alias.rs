//! Walker's alias method (Vose's construction, as pbrt-v4's `AliasTable`): picks one of `n`
//! items with probability proportional to its weight in O(1) from one uniform number.
//!
//! Written here rather than taken from `rand_distr::WeightedAliasIndex`: that one draws from an
//! `Rng`, while every random number here is a hashed, stratified sample value, and light
//! selection needs the probability of an item (for MIS) as well as the draw.

/// One bin: its own item is kept with probability `q`, otherwise the draw goes to `alias`.
#[derive(Clone, Copy, Debug, Default)]
struct Bin {
    q: f32,
    alias: u32,
    pmf: f32,
}

/// A discrete distribution sampled by the alias method.
#[derive(Clone, Debug, Default)]
pub struct AliasTable {
    bins: Vec<Bin>,
}

impl AliasTable {
    /// `weights` must be finite; negative ones count as 0. An empty or all-zero list samples
    /// nothing.
    pub fn new(weights: &[f32]) -> AliasTable {
        let sum: f64 = weights.iter().map(|&w| w.max(0.0) as f64).sum();
        if sum.is_nan() || sum <= 0.0 {
            return AliasTable::default();
        }
        let n = weights.len();
        let pmf: Vec<f64> = weights.iter().map(|&w| w.max(0.0) as f64 / sum).collect();
        let mut bins: Vec<Bin> = pmf
            .iter()
            .map(|&p| Bin {
                q: 0.0,
                alias: 0,
                pmf: p as f32,
            })
            .collect();
        // Scaled probabilities p * n: under 1 the bin needs an alias, over 1 it gives one.
        let mut scaled: Vec<f64> = pmf.iter().map(|&p| p * n as f64).collect();
        let (mut under, mut over): (Vec<usize>, Vec<usize>) =
            (0..n).partition(|&i| scaled[i] < 1.0);
        while let (Some(&u), Some(&o)) = (under.last(), over.last()) {
            under.pop();
            bins[u].q = scaled[u] as f32;
            bins[u].alias = o as u32;
            scaled[o] -= 1.0 - scaled[u];
            if scaled[o] < 1.0 {
                over.pop();
                under.push(o);
            }
        }
        // What is left is 1 up to rounding.
        for i in under.into_iter().chain(over) {
            bins[i].q = 1.0;
            bins[i].alias = i as u32;
        }
        AliasTable { bins }
    }

    pub fn len(&self) -> usize {
        self.bins.len()
    }

    pub fn is_empty(&self) -> bool {
        self.bins.is_empty()
    }

    /// Probability of item `i` (0 outside the table).
    pub fn pmf(&self, i: usize) -> f32 {
        self.bins.get(i).map_or(0.0, |b| b.pmf)
    }

    /// The item for `u` in [0, 1) and its probability; `None` for an empty table.
    pub fn sample(&self, u: f32) -> Option<(usize, f32)> {
        let n = self.bins.len();
        if n == 0 {
            return None;
        }
        let x = u * n as f32;
        let k = (x as usize).min(n - 1);
        let up = (x - k as f32).clamp(0.0, 1.0);
        let b = self.bins[k];
        let i = if up < b.q { k } else { b.alias as usize };
        Some((i, self.bins[i].pmf))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every item is drawn in proportion to its weight (exactly, on a fine grid of `u`), and
    /// zero weights are never drawn.
    #[test]
    fn draws_in_proportion_to_weight() {
        let w = [1.0, 0.0, 3.0, 0.5, 2.5, 0.0, 7.0];
        let t = AliasTable::new(&w);
        let sum: f32 = w.iter().sum();
        let n = 700_000;
        let mut counts = [0u32; 7];
        for k in 0..n {
            let (i, p) = t.sample((k as f32 + 0.5) / n as f32).unwrap();
            assert!((p - w[i] / sum).abs() < 1e-6);
            counts[i] += 1;
        }
        for i in 0..7 {
            let got = counts[i] as f32 / n as f32;
            assert!((got - w[i] / sum).abs() < 1e-4, "item {i}: {got}");
            assert!((t.pmf(i) - w[i] / sum).abs() < 1e-6);
        }
        assert!(AliasTable::new(&[0.0, 0.0]).sample(0.3).is_none());
        assert!(AliasTable::new(&[]).sample(0.3).is_none());
        assert_eq!(AliasTable::new(&[2.0]).sample(0.99), Some((0, 1.0)));
    }
}
