//! The layer's weight adaptation and relevance tracking (docs/method.md sections 3 and 4).

use super::super::config::Integrator;
use super::super::kernels;
use super::super::RbfError;
use super::GaussianRbfLayer;

impl GaussianRbfLayer {
    // ------------------------------------------------------------------------------------
    // Adaptation (docs/method.md section 3)
    // ------------------------------------------------------------------------------------

    /// One step of the update law `W' = Gamma (S(Z) e^T - sigma W)` (docs/method.md section 3,
    /// the corrected eq. 27) over `dt`, with `S(Z)` the stored activations and `e` (length
    /// `n`, e2 in docs/method.md) held constant over the step. The integrator is
    /// [`Integrator::ExactDecay`] by default (`W <- a W + (1 - a)/sigma S e^T`,
    /// `a = exp(-Gamma sigma dt)`) or [`Integrator::Euler`].
    ///
    /// Refused, with the weights untouched, if `e` is not finite, `dt` is negative or not
    /// finite, lengths do not match, or there are no valid activations.
    pub fn adapt(&mut self, e: &[f64], dt: f64) -> Result<(), RbfError> {
        Self::check_len("error e", self.outputs, e.len())?;
        if !e.iter().all(|x| x.is_finite()) {
            return Err(RbfError::NonFiniteError);
        }
        if !(dt.is_finite() && dt >= 0.0) {
            return Err(RbfError::InvalidStep(dt));
        }
        if !self.activations_valid {
            return Err(RbfError::NoActivations);
        }
        let (decay, gain) = self.step_coefficients(dt);
        let len = self.len;
        kernels::update(
            self.isa,
            &self.activations[..len],
            &mut self.weights[..len * self.outputs],
            e,
            decay,
            gain,
        );
        Ok(())
    }

    /// One controller step: [`activate`](Self::activate) at `z`, `out = f_hat(z) = W^T S(z)`
    /// with the weights **before** the update (eq. 10), then the update-law step of
    /// [`adapt`](Self::adapt) with error `e` over `dt` (docs/method.md section 3). The result is
    /// identical, bit for bit, to `evaluate(z, out)` followed by `adapt(e, dt)`.
    ///
    /// Errors: wrong lengths and a non-finite `z` are reported before anything is written
    /// (as [`evaluate`](Self::evaluate) does). A non-finite `e` or an invalid `dt` is
    /// reported **after** the output has been computed: `out` and the activations are
    /// valid, only the adaptation was skipped (the weights are untouched).
    pub fn evaluate_adapt(
        &mut self,
        z: &[f64],
        e: &[f64],
        dt: f64,
        out: &mut [f64],
    ) -> Result<(), RbfError> {
        Self::check_len("output", self.outputs, out.len())?;
        Self::check_len("error e", self.outputs, e.len())?;
        self.activate(z)?;
        if !e.iter().all(|x| x.is_finite()) {
            self.output(out)?;
            return Err(RbfError::NonFiniteError);
        }
        if !(dt.is_finite() && dt >= 0.0) {
            self.output(out)?;
            return Err(RbfError::InvalidStep(dt));
        }
        let (decay, gain) = self.step_coefficients(dt);
        let len = self.len;
        out.fill(0.0);
        let act = &self.activations[..len];
        let weights = &mut self.weights[..len * self.outputs];
        kernels::accumulate(self.isa, act, weights, out);
        kernels::update(self.isa, act, weights, e, decay, gain);
        Ok(())
    }

    /// `(a, b)` with `W <- a W + b S e^T` for one step of length `dt`.
    pub(super) fn step_coefficients(&self, dt: f64) -> (f64, f64) {
        let x = self.gamma * self.sigma * dt;
        match self.integrator {
            Integrator::Euler => (1.0 - x, self.gamma * dt),
            Integrator::ExactDecay => {
                if x > 0.0 {
                    // (1 - exp(-Gamma sigma dt)) / sigma, accurate for small arguments.
                    ((-x).exp(), -(-x).exp_m1() / self.sigma)
                } else {
                    (1.0, self.gamma * dt)
                }
            }
        }
    }

    // ------------------------------------------------------------------------------------
    // Relevance and discard (docs/method.md section 4, eq. 29-31)
    // ------------------------------------------------------------------------------------

    /// Records the stored activations in the relevance tracker (docs/method.md section 4).
    ///
    /// Definition (two-bucket trailing maximum): steps are grouped into buckets of `W` =
    /// `relevance_window` tracked steps. Each node keeps the maximum of its activation over
    /// the current bucket and over the previous complete bucket; its relevance
    /// ([`relevance`](Self::relevance)) is the larger of the two, i.e. the maximum activation
    /// over the last `W + k` tracked steps, where `k in [0, W)` is the number of steps in the
    /// current bucket (and over its whole life if it was added more recently). Cost: one
    /// `max` per node per step, and an `O(L)` rotation every `W` steps.
    ///
    /// Returns [`RbfError::NoActivations`] (and records nothing) when the last input was
    /// invalid.
    pub fn track_relevance(&mut self) -> Result<(), RbfError> {
        if !self.activations_valid {
            return Err(RbfError::NoActivations);
        }
        let len = self.len;
        for (r, &s) in self.relevance_current[..len]
            .iter_mut()
            .zip(&self.activations[..len])
        {
            // Activations are never NaN (the Gaussian maps NaN to 0), so the plain
            // comparison is `max`; unlike `f64::max` (NaN rules) or a conditional store it
            // compiles to vector max instructions.
            *r = if s > *r { s } else { *r };
        }
        self.tracked_steps = self.tracked_steps.saturating_add(1);
        self.window_fill += 1;
        if self.window_fill >= self.window {
            std::mem::swap(&mut self.relevance_current, &mut self.relevance_previous);
            self.relevance_current[..len].fill(0.0);
            self.window_fill = 0;
        }
        Ok(())
    }
}
