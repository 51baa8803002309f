//! The estimate's first-order low-pass (`observer.cutoff_hz`; docs/method.md section 5, the
//! learned observer's `LP`): the one filter every front end and experiment script applies
//! to an observer's estimate, so none re-implements it.

use crate::error::LoopError;

/// First-order low-pass `y += alpha (x - y)`, `alpha = dt / (dt + 1 / (2 pi f_c))`, per
/// joint, from rest; `f_c = 0` passes the input through.
#[derive(Clone, Debug)]
pub struct EstimateLowPass {
    alpha: f64,
    y: Vec<f64>,
}

impl EstimateLowPass {
    /// `n` joints at `rate_hz`; an error at `observer.cutoff_hz` for a cut-off that is not a
    /// finite number >= 0, at `control_rate_hz` for a rate that is not > 0.
    pub fn new(n: usize, cutoff_hz: f64, rate_hz: f64) -> Result<Self, LoopError> {
        if !(cutoff_hz.is_finite() && cutoff_hz >= 0.0) {
            return Err(LoopError::invalid(
                "observer.cutoff_hz",
                format!("is {cutoff_hz}, must be >= 0 (0: no filter)"),
            ));
        }
        if !(rate_hz.is_finite() && rate_hz > 0.0) {
            return Err(LoopError::invalid(
                "control_rate_hz",
                format!("is {rate_hz}, must be > 0"),
            ));
        }
        Ok(Self {
            alpha: Self::alpha(cutoff_hz, rate_hz),
            y: vec![0.0; n],
        })
    }

    /// The filter's gain per sample at `rate_hz` (1 when `cutoff_hz` is 0).
    pub fn alpha(cutoff_hz: f64, rate_hz: f64) -> f64 {
        if cutoff_hz > 0.0 {
            let dt = 1.0 / rate_hz;
            dt / (dt + 1.0 / (2.0 * std::f64::consts::PI * cutoff_hz))
        } else {
            1.0
        }
    }

    /// One sample of the filter with gain `alpha` on a state the caller holds.
    #[inline]
    pub fn step(alpha: f64, raw: &[f64], estimate: &mut [f64]) {
        for (e, r) in estimate.iter_mut().zip(raw) {
            *e += alpha * (r - *e);
        }
    }

    /// Filters one sample (`raw.len()` must be `n`); returns the filtered estimate.
    pub fn update(&mut self, raw: &[f64]) -> &[f64] {
        Self::step(self.alpha, raw, &mut self.y);
        &self.y
    }

    /// Back to rest (zero).
    pub fn reset(&mut self) {
        self.y.fill(0.0);
    }

    /// Number of joints.
    pub fn n(&self) -> usize {
        self.y.len()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_step_response_is_the_first_order_one() {
        let mut f = EstimateLowPass::new(1, 5.0, 1000.0).unwrap();
        let a = EstimateLowPass::alpha(5.0, 1000.0);
        let mut y = 0.0;
        for _ in 0..100 {
            y += a * (1.0 - y);
            assert_eq!(f.update(&[1.0])[0], y);
        }
        // After one time constant (1 / (2 pi 5) s = 32 ms) about 1 - 1/e.
        let mut g = EstimateLowPass::new(1, 5.0, 1000.0).unwrap();
        let mut last = 0.0;
        for _ in 0..32 {
            last = g.update(&[1.0])[0];
        }
        assert!((last - (1.0 - (-1.0f64).exp())).abs() < 0.02, "{last}");
    }

    #[test]
    fn zero_passes_through_and_bad_values_name_their_key() {
        let mut f = EstimateLowPass::new(2, 0.0, 1000.0).unwrap();
        assert_eq!(f.update(&[3.0, -1.0]), &[3.0, -1.0]);
        let e = EstimateLowPass::new(2, -1.0, 1000.0).unwrap_err();
        assert!(e.to_string().contains("observer.cutoff_hz"), "{e}");
        let e = EstimateLowPass::new(2, 5.0, 0.0).unwrap_err();
        assert!(e.to_string().contains("control_rate_hz"), "{e}");
    }
}
