//! Centre placement (k-means++ seeding) and width heuristics for the enhancement nodes
//! (docs/method.md section 5: centres taken from the data, by k-means++ seeding or a random
//! subset of the rows; widths from a rule based on distances).
//!
//! Centres: k-means++ seeding (D^2 sampling, Arthur and Vassilvitskii 2007) on a uniform
//! random subsample of the standardised training inputs, without Lloyd iterations.
//! Why seeding: it places the first centre uniformly and every further one with
//! probability proportional to the squared distance to the nearest centre already placed,
//! so the centres spread over the whole support of the data (including the sparsely
//! visited corners of the joint box, where a uniform random subset would put almost no
//! node) while still following its density. Lloyd iterations would pull the centres back
//! into the dense regions, and they cost a full pass per iteration. Why a subsample: the
//! seeding costs O(M L d) for M candidate rows; M = 20,000 (20 per node) is plenty for
//! placing 1000 centres and takes a few tens of milliseconds, where all 450,000 rows would
//! cost as much as the feature computation of the whole fit. The subsample and the
//! sampling use a ChaCha8 generator seeded from the configuration: the result is
//! deterministic (the same on every platform).

use super::config::WidthRule;
use super::data::{Dataset, Standardiser};
use super::kernels;
use rand::seq::index;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// Standardised inputs of a uniform random subsample of `m` rows (sorted row order),
/// block-major (`kernels::block_major_index`), the layout `kernels::sqdist` reads.
pub(crate) fn subsample_standardised(
    data: &Dataset<'_>,
    std: &Standardiser,
    m: usize,
    rng: &mut ChaCha8Rng,
) -> (Vec<f64>, usize) {
    let n = data.n_samples();
    let d = data.d_in();
    let m = m.clamp(1, n);
    let mut idx = index::sample(rng, n, m).into_vec();
    idx.sort_unstable();
    let mut pts_t = vec![0.0; d * m];
    let mut row = vec![0.0; d];
    for (i, &r) in idx.iter().enumerate() {
        std.apply(data.input_row(r), &mut row);
        for k in 0..d {
            pts_t[kernels::block_major_index(m, d, k, i)] = row[k];
        }
    }
    (pts_t, m)
}

/// k-means++ seeding: chooses `count` new centres from the `m` candidate points `pts_t`
/// (block-major, `kernels::block_major_index`), given `existing` centres (row-major, may
/// be empty: then the first centre is uniform). Returns the new centres row-major (count x dim).
///
/// When every candidate coincides with a centre already chosen (fewer distinct points
/// than nodes), further centres are drawn uniformly (duplicates; the ridge term keeps
/// the normal equations positive definite).
pub(crate) fn kmeanspp(
    pts_t: &[f64],
    m: usize,
    dim: usize,
    existing: &[f64],
    count: usize,
    rng: &mut ChaCha8Rng,
) -> Vec<f64> {
    let mut out = Vec::with_capacity(count * dim);
    if count == 0 || m == 0 {
        return out;
    }
    let mut mind = vec![f64::INFINITY; m];
    let mut dist = vec![0.0; m];
    let mut c = vec![0.0; dim];
    let update = |centre: &[f64], mind: &mut [f64], dist: &mut [f64]| {
        kernels::sqdist(centre, pts_t, dist);
        for (a, &b) in mind.iter_mut().zip(dist.iter()) {
            if b < *a {
                *a = b;
            }
        }
    };
    for centre in existing.chunks_exact(dim.max(1)) {
        update(centre, &mut mind, &mut dist);
    }
    for _ in 0..count {
        let total: f64 = if existing.is_empty() && out.is_empty() {
            0.0
        } else {
            mind.iter().sum()
        };
        let pick = if total > 0.0 && total.is_finite() {
            let r = rng.random::<f64>() * total;
            let mut acc = 0.0;
            let mut pick = m - 1;
            for (i, &v) in mind.iter().enumerate() {
                acc += v;
                if acc > r {
                    pick = i;
                    break;
                }
            }
            // Never pick a point with zero weight (can happen only through rounding at the end).
            if mind[pick] == 0.0 {
                pick = mind.iter().rposition(|&v| v > 0.0).unwrap_or(pick);
            }
            pick
        } else {
            rng.random_range(0..m)
        };
        for k in 0..dim {
            c[k] = pts_t[kernels::block_major_index(m, dim, k, pick)];
        }
        out.extend_from_slice(&c);
        update(&c, &mut mind, &mut dist);
    }
    out
}

fn median(v: &mut [f64]) -> Option<f64> {
    if v.is_empty() {
        return None;
    }
    v.sort_unstable_by(|a, b| a.total_cmp(b));
    let n = v.len();
    Some(if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    })
}

/// Widths of the nodes `start..L` of `centres` (row-major L x dim, standardised units),
/// using all L centres as neighbours. `existing_widths` (the widths of nodes
/// `0..start`) only serve as a fallback. See [`WidthRule`] for the rules.
///
/// Fallbacks: a width that comes out zero or non-finite (duplicate centres) becomes the
/// median of the positive widths (new and existing); with a single node and no
/// neighbour, or no positive width at all, the width is `sqrt(dim)` (the expected
/// distance of a standardised point from the mean) times the rule's scale.
pub(crate) fn compute_widths(
    centres: &[f64],
    dim: usize,
    start: usize,
    existing_widths: &[f64],
    rule: &WidthRule,
) -> Vec<f64> {
    let l = centres.len().checked_div(dim).unwrap_or(0);
    let count = l.saturating_sub(start);
    let row = |j: usize| &centres[j * dim..(j + 1) * dim];
    let d2 = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(x, y)| (x - y) * (x - y)).sum::<f64>();
    let default_scale = match rule {
        WidthRule::Knn { scale, .. } | WidthRule::GlobalMedian { scale } => *scale,
        WidthRule::Fixed(_) => 1.0,
    };
    let mut widths = match rule {
        WidthRule::Fixed(w) => vec![*w; count],
        WidthRule::Knn { k, scale } => {
            let kk = (*k).min(l.saturating_sub(1));
            let mut ds = Vec::with_capacity(l);
            (start..l)
                .map(|j| {
                    if kk == 0 {
                        return 0.0;
                    }
                    ds.clear();
                    ds.extend((0..l).filter(|&i| i != j).map(|i| d2(row(i), row(j))));
                    ds.select_nth_unstable_by(kk - 1, |a, b| a.total_cmp(b));
                    scale * ds[..kk].iter().map(|v| v.sqrt()).sum::<f64>() / kk as f64
                })
                .collect()
        }
        WidthRule::GlobalMedian { scale } => {
            let mut nn: Vec<f64> = (0..l)
                .map(|j| {
                    (0..l)
                        .filter(|&i| i != j)
                        .map(|i| d2(row(i), row(j)))
                        .fold(f64::INFINITY, f64::min)
                        .sqrt()
                })
                .filter(|v| v.is_finite() && *v > 0.0)
                .collect();
            let w = median(&mut nn).map(|m| scale * m).unwrap_or(0.0);
            vec![w; count]
        }
    };
    let bad = |w: f64| !(w.is_finite() && w > 0.0);
    if widths.iter().any(|&w| bad(w)) {
        let mut good: Vec<f64> = widths
            .iter()
            .chain(existing_widths.iter())
            .copied()
            .filter(|&w| !bad(w))
            .collect();
        let fallback = median(&mut good).unwrap_or(default_scale * (dim.max(1) as f64).sqrt());
        for w in &mut widths {
            if bad(*w) {
                *w = fallback;
            }
        }
    }
    widths
}

/// Deterministic generator for the centre placement.
pub(crate) fn rng_from_seed(seed: u64) -> ChaCha8Rng {
    ChaCha8Rng::seed_from_u64(seed)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn kmeanspp_spreads_over_clusters() {
        // Three tight clusters far apart: k-means++ with 3 centres puts one in each.
        let m = 300;
        let mut pts = vec![0.0; 2 * m];
        for i in 0..m {
            let c = (i % 3) as f64 * 10.0;
            pts[2 * i] = c + (i as f64 * 0.37).sin() * 0.01;
            pts[2 * i + 1] = -c + (i as f64 * 0.91).cos() * 0.01;
        }
        let pts_t = kernels::block_major(&pts, 2, m);
        for seed in 0..20 {
            let mut rng = rng_from_seed(seed);
            let c = kmeanspp(&pts_t, m, 2, &[], 3, &mut rng);
            let mut clusters: Vec<i64> =
                c.chunks(2).map(|p| (p[0] / 10.0).round() as i64).collect();
            clusters.sort();
            assert_eq!(clusters, vec![0, 1, 2], "seed {seed}: {c:?}");
        }
        // With two clusters already covered by existing centres, the new one goes to the third.
        let mut rng = rng_from_seed(1);
        let c = kmeanspp(&pts_t, m, 2, &[0.0, 0.0, 10.0, -10.0], 1, &mut rng);
        assert!(
            (c[0] - 20.0).abs() < 0.1 && (c[1] + 20.0).abs() < 0.1,
            "{c:?}"
        );
    }

    #[test]
    fn knn_widths() {
        // Four centres on a line at 0, 1, 3, 7 (dim 1).
        let c = [0.0, 1.0, 3.0, 7.0];
        let w = compute_widths(&c, 1, 0, &[], &WidthRule::Knn { k: 2, scale: 1.0 });
        assert_eq!(w, vec![2.0, 1.5, 2.5, 5.0]);
        let w = compute_widths(&c, 1, 2, &[9.0, 9.0], &WidthRule::Knn { k: 1, scale: 2.0 });
        assert_eq!(w, vec![4.0, 8.0]);
        let w = compute_widths(&c, 1, 0, &[], &WidthRule::GlobalMedian { scale: 1.0 });
        assert_eq!(w, vec![1.5; 4]);
        // Duplicates: zero widths fall back to the median of the positive ones.
        let c = [0.0, 0.0, 5.0, 5.0, 9.0];
        let w = compute_widths(&c, 1, 0, &[], &WidthRule::Knn { k: 1, scale: 1.0 });
        assert_eq!(w, vec![4.0, 4.0, 4.0, 4.0, 4.0]);
        // A single node: sqrt(dim) * scale.
        let w = compute_widths(
            &[1.0, 2.0, 3.0, 4.0],
            4,
            0,
            &[],
            &WidthRule::Knn { k: 3, scale: 1.5 },
        );
        assert_eq!(w, vec![3.0]);
    }
}
