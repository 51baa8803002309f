//! Tests of the packed products against plain loops.

use super::*;

use super::super::test_values as values;

/// Checks `c[j * ldc + i] == before + sum_s A[ra + i, s] A[rb + j, s]` (samples s0..,
/// k of them, from the column-major block `at`, leading dimension ld) where `keep(i,
/// j)`, and `c == before` everywhere else, to 1e-13 of `sum_s |A A|`.
#[allow(clippy::too_many_arguments)]
fn check_product(
    c: &[f64],
    ldc: usize,
    before: f64,
    at: &[f64],
    ld: usize,
    (ra, m): (usize, usize),
    (rb, n): (usize, usize),
    (s0, k): (usize, usize),
    keep: impl Fn(usize, usize) -> bool,
    what: &str,
) {
    for (idx, &v) in c.iter().enumerate() {
        let (i, j) = (idx % ldc, idx / ldc);
        if i < m && j < n && keep(i, j) {
            let (mut e, mut scale) = (0.0, 0.0);
            for s in s0..s0 + k {
                let t = at[s * ld + ra + i] * at[s * ld + rb + j];
                e += t;
                scale += t.abs();
            }
            let err = (v - before - e).abs();
            assert!(
                err <= 1e-13 * scale + 1e-15,
                "{what}: C[{i}, {j}] = {v}, expected {} (error {err:e}, scale {scale:e})",
                before + e
            );
        } else {
            assert_eq!(v, before, "{what}: C[{i}, {j}] must be untouched");
        }
    }
}

type Product = fn(&mut [f64], usize, &Slab, &Slab, Store);

/// Both entry points: the dispatching one (the AVX2 + FMA kernel where the CPU has
/// it) and the portable loops.
fn paths() -> [(&'static str, Product); 2] {
    [("gemm_nt", gemm_nt), ("gemm_nt_portable", gemm_nt_portable)]
}

#[test]
fn lower_triangle_matches_naive_on_awkward_sizes() {
    for &(p, k) in &[
        (1, 1),
        (2, 3),
        (5, 1),
        (7, 4),
        (8, 9),
        (13, 17),
        (24, 5),
        (25, 2),
        (51, 33),
        (100, 1),
        (203, 300),
    ] {
        // Two samples before the packed range, a leading dimension above P.
        let (ld, s0) = (p + 3, 2);
        let at = values(ld * (s0 + k), (p * 1000 + k) as u64);
        let mut slab = Slab::new(p, k);
        slab.pack(&at, ld, 0, s0, k);
        for (what, f) in paths() {
            let ldc = p + 2;
            let mut c = vec![0.25; ldc * p];
            f(&mut c, ldc, &slab, &slab, Store::AddLower);
            let what = format!("{what} lower P {p} k {k}");
            check_product(
                &c,
                ldc,
                0.25,
                &at,
                ld,
                (0, p),
                (0, p),
                (s0, k),
                |i, j| i >= j,
                &what,
            );
        }
    }
}

#[test]
fn cross_product_matches_naive_on_awkward_sizes() {
    // A: all P rows; B: the last kn rows (a node growth's new columns).
    for &(p, kn, k) in &[
        (1, 1, 1),
        (9, 1, 5),
        (13, 6, 7),
        (30, 7, 1),
        (61, 13, 40),
        (150, 25, 257),
    ] {
        let ld = p;
        let at = values(ld * k, (p * 7 + kn * 3 + k) as u64);
        let mut all = Slab::new(p, k);
        let mut new = Slab::new(kn, k);
        all.pack(&at, ld, 0, 0, k);
        new.pack(&at, ld, p - kn, 0, k);
        for (what, f) in paths() {
            let ldc = p + 1;
            let mut c = vec![-1.5; ldc * kn];
            f(&mut c, ldc, &all, &new, Store::Add);
            let what = format!("{what} cross P {p} new {kn} k {k}");
            check_product(
                &c,
                ldc,
                -1.5,
                &at,
                ld,
                (0, p),
                (p - kn, kn),
                (0, k),
                |_, _| true,
                &what,
            );
        }
    }
}

#[test]
fn a_slab_is_reused_with_fewer_samples() {
    let (p, cap) = (37, 64);
    let at = values(p * 100, 3);
    let mut slab = Slab::new(p, cap);
    slab.pack(&at, p, 0, 0, cap);
    // Repacked with fewer samples: the layout is compact, no stale values are read.
    slab.pack(&at, p, 0, 70, 11);
    for (what, f) in paths() {
        let mut c = vec![0.0; p * p];
        f(&mut c, p, &slab, &slab, Store::AddLower);
        check_product(
            &c,
            p,
            0.0,
            &at,
            p,
            (0, p),
            (0, p),
            (70, 11),
            |i, j| i >= j,
            what,
        );
    }
}

#[test]
fn empty_operands_and_contractions() {
    let at = values(10, 1);
    let mut a = Slab::new(5, 2);
    a.pack(&at, 5, 0, 0, 0);
    let mut c = vec![1.0; 25];
    for (_, f) in paths() {
        f(&mut c, 5, &a, &a, Store::AddLower);
        f(&mut c, 5, &a, &a, Store::Add);
    }
    assert!(c.iter().all(|&v| v == 1.0));
    // An empty contraction overwrites with zeros.
    for (what, f) in paths() {
        let mut c = vec![1.0; 25];
        f(&mut c, 5, &a, &a, Store::Overwrite);
        assert!(c.iter().all(|&v| v == 0.0), "{what}");
    }
    let mut e = Slab::new(0, 2);
    e.pack(&at, 5, 0, 0, 2);
    a.pack(&at, 5, 0, 0, 2);
    for (_, f) in paths() {
        f(&mut c, 5, &a, &e, Store::Overwrite);
    }
    assert!(c.iter().all(|&v| v == 1.0));
}

/// `[pattern | targets]` rows and row-major operands (the distance products, scaled,
/// overwriting C) pack and multiply like the plain block.
#[test]
fn targets_rows_and_overwrite_match_naive() {
    for &(p, d, k) in &[(1, 1, 1), (6, 2, 5), (29, 7, 33), (101, 3, 256)] {
        let at = values(p * k, 5 + p as u64);
        let y = values(d * k, 6 + d as u64);
        // The same matrix as one column-major block with the targets as extra rows.
        let mut aug = vec![0.0; (p + d) * k];
        for s in 0..k {
            aug[s * (p + d)..][..p].copy_from_slice(&at[s * p..][..p]);
            aug[s * (p + d) + p..][..d].copy_from_slice(&y[s * d..][..d]);
        }
        let mut slab = Slab::new(p + d, k);
        slab.pack_with_targets(&at, p, 0, k, &y, d);
        for (what, f) in paths() {
            let n = p + d;
            let mut c = vec![0.5; n * n];
            f(&mut c, n, &slab, &slab, Store::AddLower);
            let what = format!("{what} targets P {p} d {d} k {k}");
            check_product(
                &c,
                n,
                0.5,
                &aug,
                n,
                (0, n),
                (0, n),
                (0, k),
                |i, j| i >= j,
                &what,
            );
        }
        // Row-major operands: rows of `aug^T` (samples), contraction over the rows.
        let (m, n) = (p + d, k);
        let mut rows_a = Slab::new(k, m);
        rows_a.pack_rows(&aug, m, m, -2.0);
        let mut rows_b = Slab::new(k, m);
        rows_b.pack_rows(&aug, m, m, 1.0);
        for (what, f) in paths() {
            let mut c = vec![9.0; n * n];
            f(&mut c, n, &rows_a, &rows_b, Store::Overwrite);
            for j in 0..n {
                for i in 0..n {
                    let (mut e, mut scale) = (0.0, 0.0);
                    for t in 0..m {
                        let v = -2.0 * aug[i * m + t] * aug[j * m + t];
                        e += v;
                        scale += v.abs();
                    }
                    let err = (c[j * n + i] - e).abs();
                    assert!(err <= 1e-13 * scale + 1e-15, "{what} rows {i} {j}: {err:e}");
                }
            }
        }
    }
}

/// A slab written a few samples at a time holds exactly what one packing of the
/// whole block holds, and `copy_rows` cuts the same rows that packing them gives
/// (including the zero rows that pad the last panels). Compared bit for bit.
#[test]
fn chunked_writes_and_row_copies_equal_whole_packing() {
    for &(p, d, k, cap) in &[
        (1, 1, 1, 1),
        (6, 2, 5, 8),
        (29, 7, 33, 40),
        (103, 7, 257, 300),
    ] {
        let at = values(p * k, 11 + p as u64);
        let y = values(d * k, 12 + d as u64);
        let mut whole = Slab::new(p + d, cap);
        whole.pack_with_targets(&at, p, 0, k, &y, d);
        let mut chunked = Slab::new(p + d, cap);
        // Stale contents first: every value must be overwritten.
        chunked.pack_with_targets(&values(p * cap, 99), p, 0, cap, &values(d * cap, 98), d);
        chunked.set_len(k);
        let mut s0 = 0;
        for c in [1usize, 7, 24, 3].iter().cycle() {
            if s0 == k {
                break;
            }
            let c = (*c).min(k - s0);
            chunked.write_chunk(&at[s0 * p..], p, s0, c, &y[s0 * d..], d);
            s0 += c;
        }
        assert_eq!(whole.data(), chunked.data(), "P {p} d {d} k {k}");
        for (row0, rows) in [(0, p + d), (p / 2, p - p / 2), (p + d - 1, 1)] {
            let mut cut = Slab::new(rows, cap);
            cut.copy_rows(&whole, row0);
            let mut aug = vec![0.0; (p + d) * k];
            for s in 0..k {
                aug[s * (p + d)..][..p].copy_from_slice(&at[s * p..][..p]);
                aug[s * (p + d) + p..][..d].copy_from_slice(&y[s * d..][..d]);
            }
            let mut packed = Slab::new(rows, cap);
            packed.pack(&aug, p + d, row0, 0, k);
            assert_eq!(
                cut.data(),
                packed.data(),
                "rows {row0}.. of P {p} d {d} k {k}"
            );
        }
    }
}
