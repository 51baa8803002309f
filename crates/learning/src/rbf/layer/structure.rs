//! Changing the layer's nodes: discard, removal, addition and growth (docs/method.md section 4).

use std::cmp::Ordering;

use super::super::config::GrowthParams;
use super::super::kernels::{self, centre_slot, gaussian, sq_dist, Nodes};
use super::super::RbfError;
use super::{inverse_width_sq, GaussianRbfLayer, GrowOutcome};

impl GaussianRbfLayer {
    /// Removes every node whose tracked activation stayed below `threshold` (`Upsilon`,
    /// docs/method.md section 4 and eq. 31; 0.05 in the paper) over the trailing window, together
    /// with its centre, width and weights, and returns how many were removed.
    ///
    /// A node is removed iff it has been tracked for at least `W` steps
    /// ([`observed_steps`](Self::observed_steps) `>= relevance_window`) and its
    /// [`relevance`](Self::relevance) is `< threshold`; younger nodes are kept (a node is
    /// never judged on less than a full window). Storage is compacted in place; surviving
    /// nodes keep their relative order and their (centre, width, weights, relevance)
    /// unchanged, so the output of the remaining nodes is unchanged. A NaN threshold removes
    /// nothing.
    pub fn discard(&mut self, threshold: f64) -> usize {
        let window = self.window as u64;
        self.retain_nodes(|layer, i| {
            let rel = layer.relevance_current[i].max(layer.relevance_previous[i]);
            let observed = layer.tracked_steps - layer.born_at[i];
            !(observed >= window && rel < threshold)
        })
    }

    /// Removes node `i` with its centre, width and weights (compacting in place, order
    /// preserved; docs/method.md section 4). Returns whether it existed.
    pub fn remove_node(&mut self, i: usize) -> bool {
        if i >= self.len {
            return false;
        }
        self.retain_nodes(|_, j| j != i) == 1
    }

    /// Keeps the nodes for which `keep(self, index)` is true, compacting in place.
    fn retain_nodes(&mut self, mut keep: impl FnMut(&Self, usize) -> bool) -> usize {
        let (d, n) = (self.dim, self.outputs);
        let mut kept = 0;
        for i in 0..self.len {
            if !keep(self, i) {
                continue;
            }
            if kept != i {
                self.centres.copy_within(i * d..(i + 1) * d, kept * d);
                for k in 0..d {
                    self.centres_t[centre_slot(d, k, kept)] = self.centres_t[centre_slot(d, k, i)];
                }
                self.weights.copy_within(i * n..(i + 1) * n, kept * n);
                self.widths[kept] = self.widths[i];
                self.inv_width_sq[kept] = self.inv_width_sq[i];
                self.activations[kept] = self.activations[i];
                self.dist_sq[kept] = self.dist_sq[i];
                self.relevance_current[kept] = self.relevance_current[i];
                self.relevance_previous[kept] = self.relevance_previous[i];
                self.born_at[kept] = self.born_at[i];
            }
            kept += 1;
        }
        let removed = self.len - kept;
        self.len = kept;
        removed
    }

    // ------------------------------------------------------------------------------------
    // Growth (docs/method.md section 4, eq. 20-23)
    // ------------------------------------------------------------------------------------

    /// Adds a node with centre `centre` (length `d`) and width `width`, zero weight and a
    /// fresh relevance record (docs/method.md section 4, eq. 23). Returns its index (`len() - 1`
    /// after the call). No spacing check. If the layer holds valid activations, the new
    /// node's activation at the last input is computed, so that a following
    /// [`adapt`](Self::adapt) already trains it.
    pub fn add_node(&mut self, centre: &[f64], width: f64) -> Result<usize, RbfError> {
        Self::check_len("centre", self.dim, centre.len())?;
        if !centre.iter().all(|x| x.is_finite()) {
            return Err(RbfError::NonFiniteInput);
        }
        if inverse_width_sq(width).is_none() {
            return Err(RbfError::InvalidWidth(width));
        }
        if self.len >= self.capacity {
            return Err(RbfError::AtCapacity(self.capacity));
        }
        let i = self.len;
        self.centres[i * self.dim..(i + 1) * self.dim].copy_from_slice(centre);
        self.push_prepared(width);
        Ok(i)
    }

    /// Finalises node `len` whose centre is already written: width, zero weights, relevance
    /// record, activation at the last input.
    fn push_prepared(&mut self, width: f64) {
        let (i, d, n) = (self.len, self.dim, self.outputs);
        let inv = inverse_width_sq(width).unwrap_or(1.0);
        for (k, &x) in self.centres[i * d..(i + 1) * d].iter().enumerate() {
            self.centres_t[centre_slot(d, k, i)] = x;
        }
        self.widths[i] = width;
        self.inv_width_sq[i] = inv;
        self.weights[i * n..(i + 1) * n].fill(0.0);
        self.relevance_current[i] = 0.0;
        self.relevance_previous[i] = 0.0;
        self.born_at[i] = self.tracked_steps;
        let d2 = sq_dist(&self.last_input, &self.centres[i * d..(i + 1) * d]);
        self.dist_sq[i] = d2;
        self.activations[i] = if self.activations_valid {
            gaussian(d2 * inv, self.exponent_cutoff)
        } else {
            0.0
        };
        self.len += 1;
    }

    /// Grows the layer at input `z` when it is poorly covered (docs/method.md section 4, eq.
    /// 20-22): with `p_bar` the mean distance from `z` to its `m` nearest centres
    /// (`m = params.neighbours`, clamped to `1..=max_neighbours()` and to `len()`), a node
    /// is added iff `p_bar > Xi` (`params.distance_threshold`), the layer is below capacity,
    /// and the new centre is at least `params.min_spacing` from every existing centre.
    ///
    /// The new centre is `u_near + step_fraction (z - u_near)` with `u_near` the nearest
    /// centre: exactly `z` with the default `step_fraction = 1` (the printed eq. 20 adds a
    /// distance to a point; docs/method.md section 4 fixes it this way). Its width is the mean
    /// width of the `m` neighbours (the layer's default width when the layer is empty, where
    /// `p_bar = inf`), its weight row is zero.
    ///
    /// Cost `O(L d)` (distances, the same kernel as [`activate`](Self::activate)) plus
    /// `O(L m)` (selection); no allocation.
    pub fn maybe_grow(
        &mut self,
        z: &[f64],
        params: &GrowthParams,
    ) -> Result<GrowOutcome, RbfError> {
        self.check_input(z)?;
        let nodes = Nodes {
            centres_t: &self.centres_t,
            len: self.len,
            inv_width_sq: &self.inv_width_sq,
            cutoff: self.exponent_cutoff,
        };
        kernels::sq_dists(self.isa, z, nodes, &mut self.scratch_sq);
        let m = self.select_nearest(params.neighbours, |layer, i| layer.scratch_sq[i]);
        Ok(self.grow_at(z, m, params))
    }

    /// [`maybe_grow`](Self::maybe_grow) at the last input passed to
    /// [`activate`](Self::activate), reusing the distances computed there (cost `O(L m)`).
    /// Returns [`RbfError::NoActivations`] if there is no valid last input.
    pub fn maybe_grow_at_last_input(
        &mut self,
        params: &GrowthParams,
    ) -> Result<GrowOutcome, RbfError> {
        if !self.activations_valid {
            return Err(RbfError::NoActivations);
        }
        let m = self.select_nearest(params.neighbours, |layer, i| layer.dist_sq[i]);
        // Take the input buffer out (no allocation: an empty Vec does not allocate).
        let z = std::mem::take(&mut self.last_input);
        let outcome = self.grow_at(&z, m, params);
        self.last_input = z;
        Ok(outcome)
    }

    /// Fills `nn_dist_sq[..m] / nn_index[..m]` with the `m` nearest nodes in increasing
    /// squared distance; returns `m` (clamped).
    fn select_nearest(&mut self, wanted: usize, dist_sq_of: impl Fn(&Self, usize) -> f64) -> usize {
        let m = wanted.clamp(1, self.nn_index.len()).min(self.len);
        let mut filled = 0usize;
        for i in 0..self.len {
            let d2 = dist_sq_of(self, i);
            // (Distances are never NaN: inputs and centres are finite.)
            if filled == m && d2 >= self.nn_dist_sq[m - 1] {
                continue;
            }
            // Insertion into the sorted prefix, dropping the last entry when full.
            let mut pos = if filled < m { filled } else { m - 1 };
            while pos > 0 && self.nn_dist_sq[pos - 1] > d2 {
                self.nn_dist_sq[pos] = self.nn_dist_sq[pos - 1];
                self.nn_index[pos] = self.nn_index[pos - 1];
                pos -= 1;
            }
            self.nn_dist_sq[pos] = d2;
            self.nn_index[pos] = i;
            if filled < m {
                filled += 1;
            }
        }
        filled
    }

    fn grow_at(&mut self, z: &[f64], m: usize, params: &GrowthParams) -> GrowOutcome {
        let d = self.dim;
        let (mean_distance, width) = if m == 0 {
            (f64::INFINITY, self.default_width)
        } else {
            let mut dist = 0.0;
            let mut width = 0.0;
            for k in 0..m {
                dist += self.nn_dist_sq[k].sqrt();
                width += self.widths[self.nn_index[k]];
            }
            (dist / m as f64, width / m as f64)
        };
        // Grow iff p_bar > Xi (a NaN Xi never grows).
        if mean_distance.partial_cmp(&params.distance_threshold) != Some(Ordering::Greater) {
            return GrowOutcome::Covered { mean_distance };
        }
        if self.len >= self.capacity {
            return GrowOutcome::AtCapacity { mean_distance };
        }
        // Candidate centre, written straight into the free slot `len`. A step fraction
        // outside (0, 1) (or NaN) means "at z".
        let slot = self.len * d;
        let frac = params.step_fraction;
        let at_z = m == 0 || !(frac > 0.0 && frac < 1.0);
        if at_z {
            self.centres[slot..slot + d].copy_from_slice(z);
        } else {
            let near = self.nn_index[0] * d;
            let (existing, free) = self.centres.split_at_mut(slot);
            let u_near = &existing[near..near + d];
            for ((c, &u), &zk) in free[..d].iter_mut().zip(u_near).zip(z) {
                *c = u + frac * (zk - u);
            }
        }
        // Spacing: distance from the candidate to the closest existing centre.
        let nearest_sq = if m == 0 {
            f64::INFINITY
        } else if at_z {
            self.nn_dist_sq[0]
        } else {
            let (existing, candidate) = self.centres.split_at(slot);
            let candidate = &candidate[..d];
            existing
                .chunks_exact(d)
                .map(|c| sq_dist(candidate, c))
                .fold(f64::INFINITY, f64::min)
        };
        let nearest = nearest_sq.sqrt();
        if nearest < params.min_spacing {
            return GrowOutcome::TooClose {
                mean_distance,
                nearest,
            };
        }
        let width = if inverse_width_sq(width).is_some() {
            width
        } else {
            self.default_width
        };
        let index = self.len;
        self.push_prepared(width);
        GrowOutcome::Added {
            index,
            mean_distance,
        }
    }
}
