#!/usr/bin/env python3
"""The broad RBF network fit of `admittance` (docs/method.md section 5) in numpy/scipy, for timing.

Reads what `crates/learning/examples/broad_train_timing.rs --out DIR` wrote (the data set,
the standardisation, the centres and widths, the chosen lambda and Rust's weights), fits the
same ridge problem as a competent numpy user would (float64, pattern rows in chunks of a
few thousand rows, Gram accumulated per chunk, Cholesky solve with scipy) and prints a JSON
line with the time of the features + Gram + solve and the relative difference of the
weights to Rust's.

    python broad_numpy.py DIR [--gram matmul|syrk] [--chunk 4096]

--gram matmul:  G += A.T @ A        (numpy dispatches A.T @ A of one buffer to BLAS syrk)
--gram syrk:    scipy.linalg.blas.dsyrk on the lower triangle, in place
"""
import argparse
import json
import os
import resource
import time

import numpy as np
import scipy.linalg as sla
from scipy.linalg.blas import dsyrk


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("dir")
    ap.add_argument("--gram", choices=["matmul", "syrk"], default="matmul")
    ap.add_argument("--chunk", type=int, default=4096)
    ap.add_argument("--repeat", type=int, default=2, help="runs; the fastest is reported")
    args = ap.parse_args()
    d = args.dir
    meta = json.load(open(os.path.join(d, "meta.json")))
    n_rows, d_in, d_out = meta["rows"], meta["d_in"], meta["d_out"]
    n_nodes, p, bias = meta["nodes"], meta["pattern_width"], meta["bias_index"]
    fcols, fscales = meta["friction_columns"], meta["friction_scales"]
    lam = meta["lambda"]

    def load(name):
        return np.fromfile(os.path.join(d, name), dtype="<f8")

    data = load("data.f64").reshape(n_rows, d_in + d_out)
    X = np.ascontiguousarray(data[:, :d_in])
    Y = np.ascontiguousarray(data[:, d_in:])
    del data
    mean, std = load("mean.f64"), load("std.f64")
    C = load("centres.f64").reshape(n_nodes, d_in)
    eta = load("widths.f64")
    w_rust = load("weights_rust.f64").reshape(p, d_out)

    runs = [fit(X, Y, mean, std, C, eta, fcols, fscales, lam, bias, p, d_in, d_out, args)
            for _ in range(max(1, args.repeat))]
    t_gram, t_total, W, cpu = min(runs, key=lambda r: r[1])
    rel = float(np.linalg.norm(W - w_rust) / np.linalg.norm(w_rust))
    print(json.dumps({
        "numpy": np.__version__,
        "gram_mode": args.gram,
        "chunk": args.chunk,
        "features_gram_s": t_gram,
        "total_s": t_total,
        "runs_s": [r[1] for r in runs],
        "cpu_s": min(r[3] for r in runs),
        "weights_rel_diff_vs_rust": rel,
        "peak_rss_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0,
    }))


def fit(X, Y, mean, std, C, eta, fcols, fscales, lam, bias, p, d_in, d_out, args):
    """Features + Gram + Cholesky solve; returns (features+Gram s, total s, W, CPU s)."""
    n_rows, n_nodes = X.shape[0], C.shape[0]
    ru0 = resource.getrusage(resource.RUSAGE_SELF)
    t0 = time.perf_counter()
    neg_inv_eta2 = -1.0 / (eta * eta)
    cn = (C * C).sum(axis=1)
    g0 = d_in + len(fcols) * len(fscales) + 1
    chunk = args.chunk
    G = np.zeros((p, p), order="F")
    ATY = np.zeros((p, d_out))
    A = np.empty((chunk, p))
    for s in range(0, n_rows, chunk):
        xb = X[s:s + chunk]
        b = xb.shape[0]
        Ab = A[:b]
        xs = (xb - mean) / std
        Ab[:, :d_in] = xs
        k = d_in
        for c in fcols:
            for v in fscales:
                np.tanh(xb[:, c] / v, out=Ab[:, k])
                k += 1
        Ab[:, k] = 1.0
        D = xs @ C.T
        D *= -2.0
        D += (xs * xs).sum(axis=1)[:, None]
        D += cn[None, :]
        np.maximum(D, 0.0, out=D)
        D *= neg_inv_eta2[None, :]
        np.exp(D, out=Ab[:, g0:])
        if args.gram == "matmul":
            G += Ab.T @ Ab
        else:
            # Ab.T is a Fortran-ordered p x b view: C = A A^T without copies, lower half.
            G = dsyrk(1.0, Ab.T, beta=1.0, c=G, trans=0, lower=1, overwrite_c=1)
        ATY += Ab.T @ Y[s:s + b]
    t_gram = time.perf_counter() - t0
    M = G
    reg = np.full(p, lam)
    reg[bias] = 0.0
    M[np.diag_indices(p)] += reg
    cf = sla.cho_factor(M, lower=True, overwrite_a=True, check_finite=False)
    W = sla.cho_solve(cf, ATY, check_finite=False)
    t_total = time.perf_counter() - t0
    ru1 = resource.getrusage(resource.RUSAGE_SELF)
    cpu = (ru1.ru_utime - ru0.ru_utime) + (ru1.ru_stime - ru0.ru_stime)
    return t_gram, t_total, W, cpu


if __name__ == "__main__":
    main()
