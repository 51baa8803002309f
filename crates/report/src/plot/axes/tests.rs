use super::*;
use crate::figures::{Line, Panel};

fn line(x: Vec<f64>, y: Vec<f64>) -> Line {
    Line {
        label: "l".into(),
        x,
        y,
        ..Line::default()
    }
}

fn panel(lines: Vec<Line>) -> Panel {
    Panel {
        lines,
        ..Panel::default()
    }
}

fn times(n: usize) -> Vec<f64> {
    (0..n).map(|k| k as f64 * 0.1).collect()
}

#[test]
fn tick_labels() {
    assert_eq!(tick_label(-0.0001, 0.5), "0");
    assert_eq!(tick_label(-0.25, 0.05), "-0.25");
    assert_eq!(tick_label(300.0, 50.0), "300");
    assert_eq!(tick_label(1.5, 0.5), "1.5");
    assert_eq!(tick_label(0.0012, 0.0002), "0.0012");
    assert_eq!(tick_label(1.5e-5, 5e-6), "1.5e-5");
    assert_eq!(tick_label(2.4e9, 2e8), "2.4e9");
}

#[test]
fn ticks_are_round_and_bounded() {
    let (ticks, step) = nice_ticks(-1.07, 2.13, 7);
    assert_eq!(step, 0.5);
    assert_eq!(ticks, [-1.0, -0.5, 0.0, 0.5, 1.0, 1.5, 2.0]);
    // Any finite range gives a bounded count; a degenerate one a single tick.
    for (lo, hi) in [
        (0.0, 1e-300),
        (-1e12, 1e12),
        (1e11, 1e11 + 1e-3),
        (5.0, 5.0),
    ] {
        let (ticks, _) = nice_ticks(lo, hi, 7);
        assert!(ticks.len() <= 28, "{lo}..{hi}: {}", ticks.len());
    }
}

#[test]
fn decimation_keeps_extremes_and_order() {
    let x: Vec<f64> = (0..100_000).map(|k| k as f64 * 1e-3).collect();
    let mut y: Vec<f64> = x.iter().map(|t| (t * 3.0).sin()).collect();
    y[54_321] = 7.0;
    let idx = decimate(&x, &y, (0.0, 100.0), 1000);
    assert!(idx.len() <= 1002 && idx.len() > 500, "{}", idx.len());
    assert!(idx.windows(2).all(|w| w[0] < w[1]));
    assert!(idx.contains(&54_321));
    let short = decimate(&x[..10], &y[..10], (0.002, 0.005), 1000);
    assert_eq!(short, vec![1, 2, 3, 4, 5, 6]);
}

#[test]
fn the_y_axis_fits_the_data_not_the_legend() {
    // Data in -1..2 and a legend of many entries: the axis stays near -1..2.
    let mut lines: Vec<Line> = (0..7)
        .map(|k| line(times(50), vec![-1.0 + 3.0 * k as f64 / 6.0; 50]))
        .collect();
    lines[0].y[3] = -1.0;
    let p = &prepare(&[panel(lines)], false)[0];
    assert!(p.y.lo >= -1.3 && p.y.lo < -1.0, "{:?}", p.y);
    assert!(p.y.hi > 2.0 && p.y.hi <= 2.3, "{:?}", p.y);
}

#[test]
fn shared_ranges_cover_every_panel() {
    let a = panel(vec![line(times(10), vec![0.5; 10])]);
    let b = panel(vec![line(times(10), (0..10).map(|k| k as f64).collect())]);
    let own = prepare(&[a.clone(), b.clone()], false);
    assert!(own[0].y.hi < 1.0);
    let shared = prepare(&[a, b], true);
    assert_eq!(shared[0].y, shared[1].y);
    assert!(shared[0].y.lo < 0.0 && shared[0].y.hi > 9.0);
}

#[test]
fn samples_that_cannot_be_drawn_are_left_out_and_counted() {
    let mut y: Vec<f64> = (0..100).map(|k| (k as f64).sin()).collect();
    y[10] = f64::NAN;
    y[20] = f64::INFINITY;
    y[30] = 1e308;
    y[40] = -1e308;
    let p = &prepare(&[panel(vec![line(times(100), y)])], false)[0];
    assert!(p.y.lo > -1.2 && p.y.hi < 1.2, "{:?}", p.y);
    assert_eq!(p.notes.len(), 1);
    let note = &p.notes[0];
    assert!(note.left_out);
    assert!(
        note.text.contains("2 non-finite") && note.text.contains("2 samples beyond"),
        "{}",
        note.text
    );
    // The line breaks at each of them: 5 pieces.
    assert_eq!(p.lines[0].len(), 5);
}

#[test]
fn any_data_give_finite_axes_and_bounded_ticks() {
    let cases: Vec<(Vec<f64>, Vec<f64>)> = vec![
        (times(10), vec![f64::MAX; 10]),
        (times(10), vec![1e300; 10]),
        (times(10), vec![0.0; 10]),
        (times(10), vec![f64::NAN; 10]),
        (vec![], vec![]),
        (vec![3.0; 10], vec![1.0; 10]),
        (vec![f64::NAN; 10], vec![1.0; 10]),
        (vec![1e308; 10], vec![1.0; 10]),
        (
            times(10),
            vec![
                1e11,
                1e11 + 1e-6,
                1e11,
                1e11,
                1e11,
                1e11,
                1e11,
                1e11,
                1e11,
                1e11,
            ],
        ),
    ];
    for (x, y) in cases {
        let what = format!("x {:?}.., y {:?}..", x.first(), y.first());
        let p = &prepare(&[panel(vec![line(x, y)])], false)[0];
        for a in [&p.x, &p.y] {
            assert!(
                a.lo.is_finite() && a.hi.is_finite() && a.lo < a.hi,
                "{what}: {a:?}"
            );
            assert!(a.lo.abs() <= LIMIT && a.hi.abs() <= LIMIT, "{what}: {a:?}");
            assert!(!a.ticks.is_empty() && a.ticks.len() <= 40, "{what}: {a:?}");
        }
    }
}

#[test]
fn far_markers_do_not_flatten_the_data() {
    let mut p = panel(vec![line(
        times(10),
        vec![0.0, 1.0, 0.5, 0.2, 0.1, 0.0, 0.3, 0.9, 1.0, 0.0],
    )]);
    p.hlines = vec![
        crate::figures::Marker {
            at: 1.1,
            label: "near".into(),
        },
        crate::figures::Marker {
            at: 1e6,
            label: "far".into(),
        },
        crate::figures::Marker {
            at: f64::NAN,
            label: "nan".into(),
        },
    ];
    let d = &prepare(&[p], false)[0];
    assert!(d.y.hi > 1.1 && d.y.hi < 1.3, "{:?}", d.y);
    assert_eq!(d.hlines, [Some(1.1), None, None]);
    assert!(
        d.notes.iter().any(|n| n.text.contains("1e6")),
        "{:?}",
        d.notes
    );
}

#[test]
fn clipping_keeps_what_is_inside() {
    let line = [(0.0, 0.0), (1.0, 2.0), (2.0, 0.0)];
    let pieces = clip(&line, (0.0, 2.0), (0.0, 1.0));
    assert_eq!(pieces.len(), 2);
    assert_eq!(pieces[0], [(0.0, 0.0), (0.5, 1.0)]);
    assert_eq!(pieces[1], [(1.5, 1.0), (2.0, 0.0)]);
    assert!(clip(&[(5.0, 5.0), (6.0, 6.0)], (0.0, 1.0), (0.0, 1.0)).is_empty());
}

#[test]
fn a_transient_before_the_fit_window_is_clipped_and_said() {
    let x = times(100);
    let y: Vec<f64> = x
        .iter()
        .map(|t| if *t < 1.0 { 50.0 } else { 0.01 * t.sin() })
        .collect();
    let mut p = panel(vec![line(x, y)]);
    p.y_fit_from = Some(2.0);
    let d = &prepare(&[p], false)[0];
    assert!(d.y.hi < 0.1, "{:?}", d.y);
    assert!(d
        .notes
        .iter()
        .any(|n| !n.left_out && n.text.contains("clipped")));
    assert!(d.lines[0].iter().flatten().all(|&(_, y)| y <= d.y.hi));
}
