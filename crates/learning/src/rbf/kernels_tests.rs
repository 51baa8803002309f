//! Tests of the layer's numeric kernels (`super`).

use super::*;

fn exp_neg_through_activate(isa: Isa, x: f64) -> f64 {
    // One node at the origin, z = sqrt(x), unit width: activation exp(-x).
    let centres_t = [0.0; BLOCK];
    let inv = [1.0; BLOCK];
    let nodes = Nodes {
        centres_t: &centres_t,
        len: 1,
        inv_width_sq: &inv,
        cutoff: MAX_EXPONENT,
    };
    let mut d2 = [0.0; BLOCK];
    let mut s = [0.0; 1];
    activate(isa, &[x.sqrt()], nodes, &mut d2, &mut s);
    // Compare with the exact exponent used.
    assert!((d2[0] - x).abs() <= 1e-12 * (1.0 + x));
    s[0] / (-d2[0]).exp()
}

#[test]
fn exp_matches_std_over_the_range() {
    let mut worst: f64 = 0.0;
    let mut x = 0.0;
    while x <= MAX_EXPONENT {
        for isa in [Isa::Generic, Isa::detect()] {
            worst = worst.max((exp_neg_through_activate(isa, x) - 1.0).abs());
        }
        let direct = exp_neg::<false>(x);
        worst = worst.max(((direct - (-x).exp()) / (-x).exp()).abs());
        x += 0.0137;
    }
    assert!(worst < 1e-15, "worst relative error {worst:e}");
    assert_eq!(exp_neg::<false>(0.0), 1.0);
    assert_eq!(gaussian(MAX_EXPONENT + 1.0, MAX_EXPONENT), 0.0);
    assert_eq!(gaussian(f64::INFINITY, MAX_EXPONENT), 0.0);
    assert_eq!(gaussian(f64::NAN, MAX_EXPONENT), 0.0);
}

/// The AVX-512 build performs the AVX2 build's operations lane by lane: every kernel's
/// output is the same bits (node counts that leave an odd block, a short block and a
/// partial exp chunk; inputs far enough for some cut-off nodes).
#[cfg(target_arch = "x86_64")]
#[test]
fn avx512_equals_avx2_bit_for_bit() {
    if Isa::detect() != Isa::Avx512 {
        eprintln!("no AVX-512 on this CPU: nothing to compare");
        return;
    }
    let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<u64>>();
    for (dim, len) in [(28, 512), (22, 512), (5, 97), (13, 33), (3, 64), (1, 7)] {
        let cap = padded(len);
        let mut centres_t = vec![0.0; dim * cap];
        for i in 0..len {
            for k in 0..dim {
                centres_t[centre_slot(dim, k, i)] = ((i * dim + k) as f64 * 0.618).sin();
            }
        }
        let inv: Vec<f64> = (0..cap).map(|i| 0.5 + (i % 7) as f64 * 0.3).collect();
        let nodes = Nodes {
            centres_t: &centres_t,
            len,
            inv_width_sq: &inv,
            cutoff: 36.8,
        };
        let n = 7;
        let w0: Vec<f64> = (0..len * n).map(|k| (k as f64 * 0.77).cos()).collect();
        let e: Vec<f64> = (0..n).map(|j| 0.1 * j as f64 - 0.3).collect();
        for step in 0..20 {
            let z: Vec<f64> = (0..dim)
                .map(|k| 1.5 * ((step * dim + k) as f64 * 0.37).sin() * (step % 3) as f64)
                .collect();
            let mut out = Vec::new();
            for isa in [Isa::Avx2Fma, Isa::Avx512] {
                let (mut d2, mut act) = (vec![0.0; cap], vec![0.0; cap]);
                activate(isa, &z, nodes, &mut d2, &mut act);
                let mut d3 = vec![0.0; cap];
                sq_dists(isa, &z, nodes, &mut d3);
                let mut f = vec![0.25; n];
                accumulate(isa, &act[..len], &w0, &mut f);
                let mut w = w0.clone();
                update(isa, &act[..len], &mut w, &e, 0.999, 0.03);
                let mut p = vec![0.0; n];
                predict(isa, &z, nodes, &w0, &mut p);
                out.push((
                    bits(&d2[..len]),
                    bits(&act[..len]),
                    bits(&d3[..len]),
                    bits(&f),
                    bits(&w),
                    bits(&p),
                ));
            }
            assert!(out[0] == out[1], "dim {dim} len {len} step {step}");
        }
    }
}

#[test]
fn sq_dist_matches_naive() {
    for d in 0..40 {
        let a: Vec<f64> = (0..d).map(|k| (k as f64 * 0.37).sin()).collect();
        let b: Vec<f64> = (0..d).map(|k| (k as f64 * 0.11).cos()).collect();
        let naive: f64 = a.iter().zip(&b).map(|(x, y)| (x - y) * (x - y)).sum();
        assert!((sq_dist(&a, &b) - naive).abs() <= 1e-12 * (1.0 + naive));
    }
}

#[test]
fn output_and_update_specialisations_agree_with_dynamic() {
    for isa in [Isa::Generic, Isa::detect()] {
        for n in 1..=10usize {
            let rows = 37;
            let act: Vec<f64> = (0..rows)
                .map(|i| {
                    if i % 5 == 0 {
                        0.0
                    } else {
                        (i as f64 * 0.3).cos().abs()
                    }
                })
                .collect();
            let w: Vec<f64> = (0..rows * n).map(|k| (k as f64 * 0.7).sin()).collect();
            let mut out = vec![0.5; n];
            accumulate(isa, &act, &w, &mut out);
            let mut reference = vec![0.5; n];
            accumulate_dyn::<false>(&act, &w, &mut reference);
            for (a, b) in out.iter().zip(&reference) {
                assert!((a - b).abs() < 1e-12);
            }
            let e: Vec<f64> = (0..n).map(|j| j as f64 - 2.0).collect();
            for decay in [1.0, 0.9] {
                let mut w1 = w.clone();
                let mut w2 = w.clone();
                update(isa, &act, &mut w1, &e, decay, 0.01);
                update_dyn::<false>(&act, &mut w2, &e, decay, 0.01);
                for (a, b) in w1.iter().zip(&w2) {
                    assert!((a - b).abs() < 1e-12);
                }
            }
        }
    }
}
