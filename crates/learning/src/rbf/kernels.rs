//! Numeric kernels of the layer: squared distances, a vectorisable `exp`, output
//! accumulation and the weight update. No allocation, no panics (all slice lengths are
//! guaranteed by the layer's invariants and re-checked by slicing that cannot fail).
//!
//! Layouts: the distance kernel reads a **block-major** copy of the centres: node `i` lies in
//! block `i / BLOCK`, each block holds its `BLOCK` nodes dimension-major (`d * BLOCK`
//! values, coordinate `k` of the block's nodes side by side), and the blocks follow each
//! other ([`centre_slot`]). `BLOCK` nodes are then processed side by side in vector
//! registers while the whole copy is read as one sequential stream, which the hardware
//! prefetchers follow (a plain dimension-major copy reads `d` streams a node stride apart).
//! Weights are node-major rows of `n` values.
//!
//! Every kernel has one generic body (`*_impl::<FMA>`) compiled three times: for the
//! baseline target, and (on x86-64) inside `#[target_feature(enable = "avx2,fma")]` and
//! `#[target_feature(enable = "avx512f,avx2,fma")]` wrappers selected at run time when the
//! CPU has the features ([`Isa::detect`]). The builds compute the same formulas; the FMA
//! builds round `a * b + c` once instead of twice. The AVX2 and AVX-512 builds perform the
//! same operations lane by lane (only the vector width differs), so their results are equal
//! bit for bit (`tests::avx512_equals_avx2_bit_for_bit`).

/// Nodes processed side by side by the distance kernel: 32 with AVX2 (eight 4-wide
/// accumulators, enough independent FMA chains to hide their latency), 16 for the baseline
/// build (eight 2-wide registers). The dimension-major centre stride is a multiple of the
/// larger, [`BLOCK`].
pub(crate) const BLOCK: usize = 32;
const BLOCK_GENERIC: usize = 16;
#[cfg(target_arch = "x86_64")]
const BLOCK_AVX2: usize = 32;
/// The AVX-512 build takes the same 32-node blocks (four 8-wide registers per block), two
/// blocks side by side ([`sq_dists_pairs`]) for eight independent FMA chains.
#[cfg(target_arch = "x86_64")]
const BLOCK_AVX512: usize = 32;

/// `capacity` rounded up to a multiple of [`BLOCK`].
pub(crate) fn padded(capacity: usize) -> usize {
    capacity.div_ceil(BLOCK) * BLOCK
}

/// Position of coordinate `k` of node `i` in the block-major centre copy of a layer with
/// input dimension `dim` (see the module docs).
#[inline(always)]
pub(crate) fn centre_slot(dim: usize, k: usize, i: usize) -> usize {
    (i / BLOCK) * dim * BLOCK + k * BLOCK + i % BLOCK
}

/// Instruction set used by the kernels, detected once at layer construction.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Isa {
    /// Baseline target features (SSE2 on x86-64).
    Generic,
    /// AVX2 and FMA, verified present at run time.
    #[cfg(target_arch = "x86_64")]
    Avx2Fma,
    /// AVX-512F with AVX2 and FMA, verified present at run time.
    #[cfg(target_arch = "x86_64")]
    Avx512,
}

impl Isa {
    /// The best instruction set available on this CPU.
    pub(crate) fn detect() -> Self {
        #[cfg(target_arch = "x86_64")]
        {
            if std::arch::is_x86_feature_detected!("avx2")
                && std::arch::is_x86_feature_detected!("fma")
            {
                if std::arch::is_x86_feature_detected!("avx512f") {
                    return Isa::Avx512;
                }
                return Isa::Avx2Fma;
            }
        }
        Isa::Generic
    }
}

pub(crate) use crate::exp::MAX_EXPONENT;
use crate::exp::{exp_neg, fmadd};

/// Squared Euclidean distance `||a - b||^2` over the common length (off the hot path).
#[inline]
pub(crate) fn sq_dist(a: &[f64], b: &[f64]) -> f64 {
    let mut acc = [0.0f64; 4];
    let ca = a.chunks_exact(4);
    let cb = b.chunks_exact(4);
    let (ra, rb) = (ca.remainder(), cb.remainder());
    for (x, y) in ca.zip(cb) {
        for k in 0..4 {
            let t = x[k] - y[k];
            acc[k] += t * t;
        }
    }
    let mut tail = 0.0;
    for (x, y) in ra.iter().zip(rb) {
        let t = x - y;
        tail += t * t;
    }
    (acc[0] + acc[1]) + (acc[2] + acc[3]) + tail
}

/// Gaussian of a scaled squared distance: `exp(-x)` for `x <= cutoff`, else `0`
/// (eq. 9 with the activation cut-off).
#[inline(always)]
fn gaussian_impl<const FMA: bool>(x: f64, cutoff: f64) -> f64 {
    let s = exp_neg::<FMA>(x);
    if x <= cutoff {
        s
    } else {
        0.0
    }
}

/// Baseline build of the cut-off Gaussian, used off the hot path.
#[inline]
pub(crate) fn gaussian(x: f64, cutoff: f64) -> f64 {
    gaussian_impl::<false>(x, cutoff)
}

/// Lanes of the batched Gaussian: four 4-wide vectors with AVX2, so that four independent
/// polynomial chains hide the FMA latency. (An intrinsic loop over the same stages measured
/// no faster: 1.29 against 1.25 ns per value.)
pub(crate) const EXP_CHUNK: usize = 16;

/// `act_j = exp(-x_j)` if `x_j <= cutoff` else `0`, with `x_j = dist_sq_j * inv_width_sq_j`,
/// for one chunk of [`EXP_CHUNK`] lanes; [`crate::exp::exp_neg`] stage by stage (the same
/// operations, so the same results) so that each step is one vector instruction per four
/// lanes. A chunk whose lanes are all beyond the cut-off
/// is written as zeros without evaluating the polynomial.
#[inline(always)]
fn gaussian_chunk<const FMA: bool>(
    dist_sq: &[f64],
    inv_width_sq: &[f64],
    cutoff: f64,
    act: &mut [f64],
) {
    const L: usize = EXP_CHUNK;
    let (Some(d), Some(iw), Some(a)) = (dist_sq.get(..L), inv_width_sq.get(..L), act.get_mut(..L))
    else {
        return;
    };
    let mut x = [0.0f64; L];
    let mut any = false;
    for j in 0..L {
        x[j] = d[j] * iw[j];
        any |= x[j] <= cutoff;
    }
    if !any {
        a.fill(0.0);
        return;
    }
    let mut t = [0.0f64; L];
    let mut r = [0.0f64; L];
    for j in 0..L {
        (t[j], r[j]) = crate::exp::reduce::<FMA>(x[j]);
    }
    let mut p = [0.0f64; L];
    for j in 0..L {
        p[j] = crate::exp::poly::<FMA>(r[j]);
    }
    for j in 0..L {
        let s = crate::exp::scale(p[j], t[j]);
        a[j] = if x[j] <= cutoff { s } else { 0.0 };
    }
}

/// [`gaussian_chunk`] over `act.len()` lanes (a multiple of [`EXP_CHUNK`]; a shorter tail
/// is computed lane by lane).
#[inline(always)]
fn gaussians_impl<const FMA: bool>(
    dist_sq: &[f64],
    inv_width_sq: &[f64],
    cutoff: f64,
    act: &mut [f64],
) {
    let full = act.len() / EXP_CHUNK * EXP_CHUNK;
    for (c, a) in act.chunks_exact_mut(EXP_CHUNK).enumerate() {
        let lo = c * EXP_CHUNK;
        if let (Some(d), Some(iw)) = (dist_sq.get(lo..), inv_width_sq.get(lo..)) {
            gaussian_chunk::<FMA>(d, iw, cutoff, a);
        }
    }
    let tail = act
        .iter_mut()
        .zip(dist_sq.iter().zip(inv_width_sq))
        .skip(full);
    for (a, (&d, &iw)) in tail {
        *a = gaussian_impl::<FMA>(d * iw, cutoff);
    }
}

/// Squared distances from `z` to the `B` nodes `start..start + B` of the block-major
/// centres (`B` divides [`BLOCK`] and `start` is a multiple of `B`, so the nodes lie in one
/// block).
#[inline(always)]
fn block_sq_dist<const FMA: bool, const B: usize>(
    z: &[f64],
    centres_t: &[f64],
    start: usize,
) -> [f64; B] {
    let mut acc = [0.0f64; B];
    let mut base = centre_slot(z.len(), 0, start);
    for &zk in z {
        if let Some(block) = centres_t.get(base..base + B) {
            for j in 0..B {
                let t = zk - block[j];
                acc[j] = fmadd::<FMA>(t, t, acc[j]);
            }
        }
        base += BLOCK;
    }
    acc
}

// ----------------------------------------------------------------------------------------
// Kernels with run-time dispatch
// ----------------------------------------------------------------------------------------

/// Centres and widths of the active nodes as the kernels read them.
#[derive(Clone, Copy)]
pub(crate) struct Nodes<'a> {
    /// Block-major centres ([`centre_slot`]), `d * padded(len)` values or more.
    pub centres_t: &'a [f64],
    /// Active node count.
    pub len: usize,
    /// `1 / eta_i^2`, at least `len` values.
    pub inv_width_sq: &'a [f64],
    /// Scaled squared distance above which the activation is zero.
    pub cutoff: f64,
}

macro_rules! dispatch {
    ($isa:expr, $generic:expr, $avx2:expr, $avx512:expr) => {
        match $isa {
            // SAFETY: `Isa::Avx2Fma` is only constructed by `Isa::detect`, after checking at
            // run time that the CPU supports AVX2 and FMA.
            #[cfg(target_arch = "x86_64")]
            Isa::Avx2Fma => unsafe { $avx2 },
            // SAFETY: likewise for `Isa::Avx512` (AVX-512F, AVX2 and FMA).
            #[cfg(target_arch = "x86_64")]
            Isa::Avx512 => unsafe { $avx512 },
            Isa::Generic => $generic,
        }
    };
}

#[inline(always)]
fn sq_dists_impl<const FMA: bool, const B: usize>(
    z: &[f64],
    nodes: Nodes<'_>,
    dist_sq: &mut [f64],
) {
    let blocks = nodes.len.div_ceil(B);
    for (b, out) in dist_sq.chunks_exact_mut(B).take(blocks).enumerate() {
        out.copy_from_slice(&block_sq_dist::<FMA, B>(z, nodes.centres_t, b * B));
    }
}

/// [`sq_dists_impl`] taking two blocks of `B` nodes side by side (twice the independent
/// accumulator chains, for 8-wide registers); each node's sum is formed in the same order.
#[inline(always)]
fn sq_dists_pairs<const FMA: bool, const B: usize>(
    z: &[f64],
    nodes: Nodes<'_>,
    dist_sq: &mut [f64],
) {
    let blocks = nodes.len.div_ceil(B);
    let pairs = blocks / 2;
    for (p, out) in dist_sq.chunks_exact_mut(2 * B).take(pairs).enumerate() {
        let start = 2 * p * B;
        let mut acc0 = [0.0f64; B];
        let mut acc1 = [0.0f64; B];
        let mut base0 = centre_slot(z.len(), 0, start);
        let mut base1 = centre_slot(z.len(), 0, start + B);
        for &zk in z {
            if let (Some(b0), Some(b1)) = (
                nodes.centres_t.get(base0..base0 + B),
                nodes.centres_t.get(base1..base1 + B),
            ) {
                for j in 0..B {
                    let t0 = zk - b0[j];
                    acc0[j] = fmadd::<FMA>(t0, t0, acc0[j]);
                    let t1 = zk - b1[j];
                    acc1[j] = fmadd::<FMA>(t1, t1, acc1[j]);
                }
            }
            base0 += BLOCK;
            base1 += BLOCK;
        }
        out[..B].copy_from_slice(&acc0);
        out[B..].copy_from_slice(&acc1);
    }
    if blocks % 2 == 1 {
        let b = blocks - 1;
        if let Some(out) = dist_sq.get_mut(b * B..(b + 1) * B) {
            out.copy_from_slice(&block_sq_dist::<FMA, B>(z, nodes.centres_t, b * B));
        }
    }
}

/// The activations from the squared distances already in `dist_sq` (see [`activate_impl`]).
#[inline(always)]
fn gaussians_of_dists<const FMA: bool>(nodes: Nodes<'_>, dist_sq: &[f64], act: &mut [f64]) {
    // Whole chunks when the buffers allow (they are `padded(capacity)` long in the layer).
    let lanes = nodes.len.div_ceil(EXP_CHUNK) * EXP_CHUNK;
    let lanes = if act.len() >= lanes && nodes.inv_width_sq.len() >= lanes {
        lanes
    } else {
        nodes.len
    };
    gaussians_impl::<FMA>(dist_sq, nodes.inv_width_sq, nodes.cutoff, &mut act[..lanes]);
}

#[inline(always)]
fn activate_impl<const FMA: bool, const B: usize>(
    z: &[f64],
    nodes: Nodes<'_>,
    dist_sq: &mut [f64],
    act: &mut [f64],
) {
    sq_dists_impl::<FMA, B>(z, nodes, dist_sq);
    // Whole chunks when the buffers allow (they are `padded(capacity)` long in the layer).
    let lanes = nodes.len.div_ceil(EXP_CHUNK) * EXP_CHUNK;
    let lanes = if act.len() >= lanes && nodes.inv_width_sq.len() >= lanes {
        lanes
    } else {
        nodes.len
    };
    gaussians_impl::<FMA>(dist_sq, nodes.inv_width_sq, nodes.cutoff, &mut act[..lanes]);
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
unsafe fn activate_avx2(z: &[f64], nodes: Nodes<'_>, dist_sq: &mut [f64], act: &mut [f64]) {
    activate_impl::<true, BLOCK_AVX2>(z, nodes, dist_sq, act)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f,avx2,fma")]
unsafe fn activate_avx512(z: &[f64], nodes: Nodes<'_>, dist_sq: &mut [f64], act: &mut [f64]) {
    sq_dists_pairs::<true, BLOCK_AVX512>(z, nodes, dist_sq);
    gaussians_of_dists::<true>(nodes, dist_sq, act)
}

/// `dist_sq_i = ||z - u_i||^2` and `act_i = s_i(z)` (eq. 9) for the active nodes.
/// `dist_sq` must hold `padded(len)` values, `act` at least `len`.
pub(crate) fn activate(
    isa: Isa,
    z: &[f64],
    nodes: Nodes<'_>,
    dist_sq: &mut [f64],
    act: &mut [f64],
) {
    if dist_sq.len() < padded(nodes.len) || act.len() < nodes.len {
        return;
    }
    dispatch!(
        isa,
        activate_impl::<false, BLOCK_GENERIC>(z, nodes, dist_sq, act),
        activate_avx2(z, nodes, dist_sq, act),
        activate_avx512(z, nodes, dist_sq, act)
    )
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
unsafe fn sq_dists_avx2(z: &[f64], nodes: Nodes<'_>, dist_sq: &mut [f64]) {
    sq_dists_impl::<true, BLOCK_AVX2>(z, nodes, dist_sq)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f,avx2,fma")]
unsafe fn sq_dists_avx512(z: &[f64], nodes: Nodes<'_>, dist_sq: &mut [f64]) {
    sq_dists_pairs::<true, BLOCK_AVX512>(z, nodes, dist_sq)
}

/// `dist_sq_i = ||z - u_i||^2` for the active nodes (`dist_sq` holds `padded(len)` values).
pub(crate) fn sq_dists(isa: Isa, z: &[f64], nodes: Nodes<'_>, dist_sq: &mut [f64]) {
    if dist_sq.len() < padded(nodes.len) {
        return;
    }
    dispatch!(
        isa,
        sq_dists_impl::<false, BLOCK_GENERIC>(z, nodes, dist_sq),
        sq_dists_avx2(z, nodes, dist_sq),
        sq_dists_avx512(z, nodes, dist_sq)
    )
}

/// Rows of fixed length `N`: `out += sum_i s_i W_i`. Rows are taken four at a time
/// (row `4q + r` goes to partial sum `r`: four independent FMA chains), groups of four zero
/// activations are skipped, leftover rows go to partial sum 0; the partial sums are added as
/// `(a0 + a1) + (a2 + a3)`.
#[inline(always)]
fn accumulate_n<const FMA: bool, const N: usize>(act: &[f64], weights: &[f64], out: &mut [f64]) {
    let (mut a0, mut a1, mut a2, mut a3) = ([0.0f64; N], [0.0f64; N], [0.0f64; N], [0.0f64; N]);
    let quads = weights.chunks_exact(4 * N);
    let tail_w = quads.remainder();
    let act_quads = act.chunks_exact(4);
    let tail_s = act_quads.remainder();
    for (w, s) in quads.zip(act_quads) {
        let (s0, s1, s2, s3) = (s[0], s[1], s[2], s[3]);
        if s0 == 0.0 && s1 == 0.0 && s2 == 0.0 && s3 == 0.0 {
            continue;
        }
        for j in 0..N {
            a0[j] = fmadd::<FMA>(s0, w[j], a0[j]);
            a1[j] = fmadd::<FMA>(s1, w[N + j], a1[j]);
            a2[j] = fmadd::<FMA>(s2, w[2 * N + j], a2[j]);
            a3[j] = fmadd::<FMA>(s3, w[3 * N + j], a3[j]);
        }
    }
    for (row, &s) in tail_w.chunks_exact(N).zip(tail_s) {
        if s != 0.0 {
            for j in 0..N {
                a0[j] = fmadd::<FMA>(s, row[j], a0[j]);
            }
        }
    }
    for (j, o) in out.iter_mut().enumerate().take(N) {
        *o += (a0[j] + a1[j]) + (a2[j] + a3[j]);
    }
}

#[inline(always)]
fn accumulate_dyn<const FMA: bool>(act: &[f64], weights: &[f64], out: &mut [f64]) {
    let n = out.len();
    for (row, &s) in weights.chunks_exact(n).zip(act) {
        if s != 0.0 {
            for (o, &w) in out.iter_mut().zip(row) {
                *o = fmadd::<FMA>(s, w, *o);
            }
        }
    }
}

/// `out += W^T S` for node-major rows of length `out.len()` (specialised for 1..=8 outputs).
#[inline(always)]
fn accumulate_impl<const FMA: bool>(act: &[f64], weights: &[f64], out: &mut [f64]) {
    match out.len() {
        0 => {}
        1 => accumulate_n::<FMA, 1>(act, weights, out),
        2 => accumulate_n::<FMA, 2>(act, weights, out),
        3 => accumulate_n::<FMA, 3>(act, weights, out),
        4 => accumulate_n::<FMA, 4>(act, weights, out),
        5 => accumulate_n::<FMA, 5>(act, weights, out),
        6 => accumulate_n::<FMA, 6>(act, weights, out),
        7 => accumulate_n::<FMA, 7>(act, weights, out),
        8 => accumulate_n::<FMA, 8>(act, weights, out),
        _ => accumulate_dyn::<FMA>(act, weights, out),
    }
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
unsafe fn accumulate_avx2(act: &[f64], weights: &[f64], out: &mut [f64]) {
    accumulate_impl::<true>(act, weights, out)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f,avx2,fma")]
unsafe fn accumulate_avx512(act: &[f64], weights: &[f64], out: &mut [f64]) {
    accumulate_impl::<true>(act, weights, out)
}

/// `out += W^T S` (eq. 10) for node-major `weights` with rows of length `out.len()`.
pub(crate) fn accumulate(isa: Isa, act: &[f64], weights: &[f64], out: &mut [f64]) {
    dispatch!(
        isa,
        accumulate_impl::<false>(act, weights, out),
        accumulate_avx2(act, weights, out),
        accumulate_avx512(act, weights, out)
    )
}

/// `W_i <- decay W_i + gain s_i e` for rows of fixed length `N`, four rows at a time .
#[inline(always)]
fn update_n<const FMA: bool, const N: usize>(
    act: &[f64],
    weights: &mut [f64],
    e: &[f64],
    decay: f64,
    gain: f64,
) {
    let mut ev = [0.0f64; N];
    for (v, &x) in ev.iter_mut().zip(e) {
        *v = x;
    }
    let mut quads = weights.chunks_exact_mut(4 * N);
    let act_quads = act.chunks_exact(4);
    let tail_s = act_quads.remainder();
    for (w, s) in quads.by_ref().zip(act_quads) {
        let (s0, s1, s2, s3) = (s[0], s[1], s[2], s[3]);
        if s0 == 0.0 && s1 == 0.0 && s2 == 0.0 && s3 == 0.0 {
            if decay != 1.0 {
                for x in w.iter_mut() {
                    *x *= decay;
                }
            }
            continue;
        }
        let (g0, g1, g2, g3) = (gain * s0, gain * s1, gain * s2, gain * s3);
        for j in 0..N {
            w[j] = fmadd::<FMA>(g0, ev[j], decay * w[j]);
            w[N + j] = fmadd::<FMA>(g1, ev[j], decay * w[N + j]);
            w[2 * N + j] = fmadd::<FMA>(g2, ev[j], decay * w[2 * N + j]);
            w[3 * N + j] = fmadd::<FMA>(g3, ev[j], decay * w[3 * N + j]);
        }
    }
    for (row, &s) in quads.into_remainder().chunks_exact_mut(N).zip(tail_s) {
        if s != 0.0 {
            let g = gain * s;
            for j in 0..N {
                row[j] = fmadd::<FMA>(g, ev[j], decay * row[j]);
            }
        } else if decay != 1.0 {
            for x in row.iter_mut() {
                *x *= decay;
            }
        }
    }
}

#[inline(always)]
fn update_dyn<const FMA: bool>(act: &[f64], weights: &mut [f64], e: &[f64], decay: f64, gain: f64) {
    let n = e.len();
    if n == 0 {
        return;
    }
    for (row, &s) in weights.chunks_exact_mut(n).zip(act) {
        let g = gain * s;
        if decay == 1.0 && g == 0.0 {
            continue;
        }
        for (w, &ej) in row.iter_mut().zip(e) {
            *w = fmadd::<FMA>(g, ej, decay * *w);
        }
    }
}

/// `W_i <- decay W_i + gain s_i e` for every row (rows with `s_i = 0` are only decayed, and
/// skipped entirely when `decay == 1`); specialised for 1..=8 outputs.
#[inline(always)]
fn update_impl<const FMA: bool>(
    act: &[f64],
    weights: &mut [f64],
    e: &[f64],
    decay: f64,
    gain: f64,
) {
    match e.len() {
        0 => {}
        1 => update_n::<FMA, 1>(act, weights, e, decay, gain),
        2 => update_n::<FMA, 2>(act, weights, e, decay, gain),
        3 => update_n::<FMA, 3>(act, weights, e, decay, gain),
        4 => update_n::<FMA, 4>(act, weights, e, decay, gain),
        5 => update_n::<FMA, 5>(act, weights, e, decay, gain),
        6 => update_n::<FMA, 6>(act, weights, e, decay, gain),
        7 => update_n::<FMA, 7>(act, weights, e, decay, gain),
        8 => update_n::<FMA, 8>(act, weights, e, decay, gain),
        _ => update_dyn::<FMA>(act, weights, e, decay, gain),
    }
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
unsafe fn update_avx2(act: &[f64], weights: &mut [f64], e: &[f64], decay: f64, gain: f64) {
    update_impl::<true>(act, weights, e, decay, gain)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f,avx2,fma")]
unsafe fn update_avx512(act: &[f64], weights: &mut [f64], e: &[f64], decay: f64, gain: f64) {
    update_impl::<true>(act, weights, e, decay, gain)
}

/// One integration step of the update law, `W <- decay W + gain S e^T` (docs/method.md section 3).
pub(crate) fn update(isa: Isa, act: &[f64], weights: &mut [f64], e: &[f64], decay: f64, gain: f64) {
    dispatch!(
        isa,
        update_impl::<false>(act, weights, e, decay, gain),
        update_avx2(act, weights, e, decay, gain),
        update_avx512(act, weights, e, decay, gain)
    )
}

#[inline(always)]
fn predict_impl<const FMA: bool, const B: usize>(
    z: &[f64],
    nodes: Nodes<'_>,
    weights: &[f64],
    out: &mut [f64],
) {
    let n = out.len();
    if n == 0 {
        return;
    }
    let blocks = nodes.len.div_ceil(B);
    for b in 0..blocks {
        let start = b * B;
        let m = B.min(nodes.len - start);
        let d2 = block_sq_dist::<FMA, B>(z, nodes.centres_t, start);
        let mut act = [0.0f64; B];
        let inv = &nodes.inv_width_sq[start..start + m];
        gaussians_impl::<FMA>(&d2[..m], inv, nodes.cutoff, &mut act[..m]);
        if let Some(rows) = weights.get(start * n..(start + m) * n) {
            accumulate_impl::<FMA>(&act[..m], rows, out);
        }
    }
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
unsafe fn predict_avx2(z: &[f64], nodes: Nodes<'_>, weights: &[f64], out: &mut [f64]) {
    predict_impl::<true, BLOCK_AVX2>(z, nodes, weights, out)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f,avx2,fma")]
unsafe fn predict_avx512(z: &[f64], nodes: Nodes<'_>, weights: &[f64], out: &mut [f64]) {
    predict_impl::<true, BLOCK_AVX512>(z, nodes, weights, out)
}

/// `out += W^T S(z)` computed block by block on the stack, without touching layer state.
pub(crate) fn predict(isa: Isa, z: &[f64], nodes: Nodes<'_>, weights: &[f64], out: &mut [f64]) {
    if nodes.inv_width_sq.len() < nodes.len {
        return;
    }
    dispatch!(
        isa,
        predict_impl::<false, BLOCK_GENERIC>(z, nodes, weights, out),
        predict_avx2(z, nodes, weights, out),
        predict_avx512(z, nodes, weights, out)
    )
}

#[cfg(test)]
#[path = "kernels_tests.rs"]
mod tests;
