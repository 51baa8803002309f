//! Fuzz target: any bytes imported as an MCAP bag (the franka profile, or lbr when the
//! bytes name its topic; damage accepted or not by the input's length) either give a table
//! of finite values with consistent sizes, or an error that names the file. It must never
//! panic, abort, hang or allocate beyond the reader's and the table's limits.
#![no_main]

use std::path::PathBuf;

use admittance_bag::{check_columns, csv_text, import, ImportOptions, Profile};
use libfuzzer_sys::fuzz_target;

fn scratch() -> PathBuf {
    std::env::temp_dir().join(format!("admittance-fuzz-bag-{}.mcap", std::process::id()))
}

fuzz_target!(|bytes: &[u8]| {
    let path = scratch();
    if std::fs::write(&path, bytes).is_err() {
        return;
    }
    let lbr = bytes.windows(10).any(|w| w == b"/lbr/state");
    let profile = Profile::builtin(if lbr { "lbr" } else { "franka" })
        .unwrap()
        .unwrap();
    let options = ImportOptions {
        accept_damage: bytes.len() % 2 == 1,
        ..Default::default()
    };
    match import(&path, &profile, &options) {
        Ok(im) => {
            let t = &im.table;
            let (rows, n) = (t.len(), t.joints.len());
            assert!(rows > 0 && n > 0);
            for block in [&t.q, &t.qdot, &t.qddot, &t.tau] {
                assert_eq!(block.len(), rows * n);
                assert!(block.iter().all(|x| x.is_finite()));
            }
            if let Some((cols, v)) = &t.label {
                assert_eq!(v.len(), rows * cols.len());
                assert!(v.iter().all(|x| x.is_finite()));
            }
            assert!(t.stamps_ns.windows(2).all(|w| w[0] < w[1]));
            if check_columns(&path, t).is_ok() && rows < 10_000 {
                let text = csv_text(t);
                assert_eq!(text.lines().count(), rows + 1);
            }
        }
        Err(e) => {
            let text = e.to_string();
            assert!(text.contains(&*path.to_string_lossy()), "{text}");
        }
    }
});
