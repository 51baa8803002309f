//! Coverage: the network knows where its training data were (issue #22). Coverage 1 on
//! the training rows (all but about 1 %), 0 far from them, the faded prediction equal to
//! `predict_into` where covered and 0 far away, allocation-free, and the threshold kept
//! by the model file (files without one have no fade).

mod broad_common;

use admittance_learning::broad::{fit, BroadModel, Dataset, COVERAGE_QUANTILE};
use admittance_testkit::count_allocations;
use broad_common::{data, small_config};

#[global_allocator]
static GLOBAL: admittance_testkit::CountingAllocator = admittance_testkit::CountingAllocator;

fn model() -> (BroadModel, Vec<f64>) {
    let (x, y) = data(1500, 21, 0.05);
    let train = Dataset::new(&x, &y, 3, 2).unwrap();
    let (net, _) = fit(&train, None, &small_config(60)).unwrap();
    (net, x)
}

#[test]
fn coverage_is_one_on_the_training_rows_and_zero_far_away() {
    let (net, x) = model();
    let m0 = net
        .coverage_threshold()
        .expect("a fitted model has a threshold");
    assert!(m0 > 0.0 && m0 <= 1.0, "{m0}");
    let mut ws = net.workspace();
    let rows = x.len() / 3;
    let below = x
        .chunks_exact(3)
        .filter(|r| net.coverage(r, &mut ws).unwrap() < 1.0)
        .count();
    assert!(
        below as f64 <= COVERAGE_QUANTILE * rows as f64 + 1.0,
        "{below} of {rows}"
    );
    // Every training row is covered to at least some degree.
    let min = x
        .chunks_exact(3)
        .map(|r| net.coverage(r, &mut ws).unwrap())
        .fold(1.0f64, f64::min);
    assert!(min > 0.1, "{min}");
    for far in [[40.0, 0.0, 0.0], [-30.0, 30.0, 5.0], [0.0, 0.0, 1e6]] {
        let c = net.coverage(&far, &mut ws).unwrap();
        assert!(c < 1e-12, "{far:?}: {c}");
        let mut out = [0.0; 2];
        let c2 = net.predict_faded_into(&far, &mut out, &mut ws).unwrap();
        assert_eq!(c, c2);
        assert!(out.iter().all(|v| v.abs() < 1e-12), "{out:?}");
    }
    // Just outside the box the coverage falls smoothly, not to 0 at once.
    let edge = net.coverage(&[2.6, 0.0, 0.0], &mut ws).unwrap();
    assert!(edge > 0.0, "{edge}");
}

#[test]
fn faded_prediction_equals_prediction_where_covered() {
    let (net, x) = model();
    let mut ws = net.workspace();
    let (mut a, mut b) = ([0.0; 2], [0.0; 2]);
    for r in x.chunks_exact(3).take(200) {
        net.predict_into(r, &mut a, &mut ws).unwrap();
        let c = net.predict_faded_into(r, &mut b, &mut ws).unwrap();
        if c == 1.0 {
            assert_eq!(a, b);
        } else {
            let s = c * c * (3.0 - 2.0 * c);
            assert!((b[0] - s * a[0]).abs() <= 1e-15 * a[0].abs().max(1.0));
        }
    }
    assert!(net.coverage(&[f64::NAN, 0.0, 0.0], &mut ws).is_err());
    assert!(net.coverage(&[0.0, 0.0], &mut ws).is_err());
}

#[test]
fn faded_prediction_and_coverage_allocate_nothing() {
    let (net, x) = model();
    let mut ws = net.workspace();
    let mut out = [0.0; 2];
    let far = [40.0, 1.0, -3.0];
    let n = count_allocations(|| {
        for r in x.chunks_exact(3).take(300) {
            net.predict_faded_into(r, &mut out, &mut ws).unwrap();
            std::hint::black_box(net.coverage(r, &mut ws).unwrap());
        }
        net.predict_faded_into(&far, &mut out, &mut ws).unwrap();
    });
    assert_eq!(n, 0);
    assert!(count_allocations(|| drop(std::hint::black_box(vec![1u8; 16]))) > 0);
}

#[test]
fn the_threshold_survives_the_model_file_and_old_files_have_none() {
    let (net, x) = model();
    let bytes = net.to_bytes();
    let back = BroadModel::from_bytes(&bytes, "m.bin").unwrap();
    assert_eq!(
        back.coverage_threshold().map(f64::to_bits),
        net.coverage_threshold().map(f64::to_bits)
    );
    // The same file without the field: a file written before coverage existed.
    let h_len = u64::from_le_bytes(bytes[8..16].try_into().unwrap()) as usize;
    let header = std::str::from_utf8(&bytes[16..16 + h_len]).unwrap();
    let start = header
        .find(",\"coverage_threshold\":")
        .expect("field written");
    let end = start + header[start + 1..].find(',').unwrap() + 1;
    let old_header = format!("{}{}", &header[..start], &header[end..]);
    let mut old = b"ADMBRBF\0".to_vec();
    old.extend_from_slice(&(old_header.len() as u64).to_le_bytes());
    old.extend_from_slice(old_header.as_bytes());
    old.extend_from_slice(&bytes[16 + h_len..bytes.len() - 8]);
    let sum = admittance_learning::broad::fnv1a64(&old);
    old.extend_from_slice(&sum.to_le_bytes());
    let old = BroadModel::from_bytes(&old, "old.bin").unwrap();
    assert_eq!(old.coverage_threshold(), None);
    let mut ws = old.workspace();
    let (mut a, mut b) = ([0.0; 2], [0.0; 2]);
    let far = [40.0, 0.0, 0.0];
    assert_eq!(old.coverage(&far, &mut ws).unwrap(), 1.0);
    old.predict_into(&far, &mut a, &mut ws).unwrap();
    old.predict_faded_into(&far, &mut b, &mut ws).unwrap();
    assert_eq!(a, b);
    let _ = x;
}
