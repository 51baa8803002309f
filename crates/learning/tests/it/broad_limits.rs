//! Refusing what cannot fit before work starts, and refusing results that are not finite:
//! data beyond the magnitude limit, more nodes than rows, fits over the memory or work
//! budget.

use crate::broad_common;
use admittance_learning::broad::{
    check_budget, fit, BroadError, Budget, Dataset, FitSize, GrowthSpec, MAX_ABS_DATA_VALUE,
};
use broad_common::{data, small_config};

#[test]
fn huge_values_are_refused_naming_row_and_column() {
    let (x, mut y) = data(300, 3, 0.0);
    // Before: a torque of 1e300 gave a model with an infinite sum of squares and NaN
    // validation errors.
    y[2 * 17 + 1] = 1e300;
    match Dataset::new(&x, &y, 3, 2) {
        Err(
            e @ BroadError::OutOfRange {
                row: 17, column: 1, ..
            },
        ) => {
            assert!(e.to_string().contains("1e300"), "{e}");
            assert!(e.to_string().contains("row 17, column 1"), "{e}");
        }
        other => panic!("{other:?}"),
    }
    let (mut x, y) = data(300, 3, 0.0);
    x[3 * 5 + 2] = -2.0 * MAX_ABS_DATA_VALUE;
    assert!(matches!(
        Dataset::new(&x, &y, 3, 2),
        Err(BroadError::OutOfRange {
            what: "inputs",
            row: 5,
            column: 2,
            ..
        })
    ));
    // The limit itself is accepted; NaN stays a NonFinite error.
    x[3 * 5 + 2] = MAX_ABS_DATA_VALUE;
    assert!(Dataset::new(&x, &y, 3, 2).is_ok());
    x[3 * 5 + 2] = f64::NAN;
    assert!(matches!(
        Dataset::new(&x, &y, 3, 2),
        Err(BroadError::NonFinite {
            row: 5,
            column: 2,
            ..
        })
    ));
}

#[test]
fn more_nodes_than_rows_is_refused_before_work() {
    let (x, y) = data(200, 4, 0.01);
    let train = Dataset::new(&x, &y, 3, 2).unwrap();
    let mut cfg = small_config(201);
    cfg.lambda_grid = vec![1e-6];
    // Before: the fit ran (duplicate centres, an underdetermined system).
    match fit(&train, None, &cfg) {
        Err(
            e @ BroadError::TooManyNodes {
                nodes: 201,
                rows: 200,
            },
        ) => {
            assert!(e.to_string().contains("201 nodes"), "{e}")
        }
        other => panic!("{other:?}"),
    }
    // Growth past the rows likewise.
    cfg.nodes = 190;
    let (mut m, _) = fit(&train, None, &cfg).unwrap();
    let spec = GrowthSpec::KMeansPlusPlus { count: 11, seed: 1 };
    assert!(matches!(
        m.grow(&train, &spec, &cfg),
        Err(BroadError::TooManyNodes {
            nodes: 201,
            rows: 200
        })
    ));
    assert_eq!(m.n_nodes(), 190);
}

#[test]
fn fits_over_the_budget_are_refused_with_the_figure() {
    let (x, y) = data(2000, 4, 0.01);
    let train = Dataset::new(&x, &y, 3, 2).unwrap();
    let mut cfg = small_config(1500);
    cfg.lambda_grid = vec![1e-6];
    cfg.budget = Budget {
        max_memory_bytes: 10_000_000,
        ..Budget::default()
    };
    let size = FitSize::fit(2000, 0, 3, 2, &cfg);
    let estimate = check_budget(&size, &Budget::unlimited()).unwrap();
    // Three P^2 matrices of 8 bytes at P = 1504: 54 MB.
    assert!(estimate.memory_bytes > 3 * 8 * 1504 * 1504, "{estimate:?}");
    match fit(&train, None, &cfg) {
        Err(
            e @ BroadError::MemoryBudget {
                needed_bytes: Some(b),
                limit_bytes: 10_000_000,
                ..
            },
        ) => {
            assert_eq!(b, estimate.memory_bytes);
            let msg = e.to_string();
            assert!(msg.contains("1500 nodes need 55 MB"), "{msg}");
            assert!(msg.contains("limit of 10 MB"), "{msg}");
        }
        other => panic!("{other:?}"),
    }
    cfg.budget = Budget {
        max_flop: 1e6,
        ..Budget::default()
    };
    assert!(matches!(
        fit(&train, None, &cfg),
        Err(BroadError::WorkBudget { .. })
    ));
}
