//! The committed C header equals a fresh cbindgen generation from the sources
//! (`ADM_BLESS=1` rewrites it instead of comparing).

use std::path::Path;

#[test]
fn header_is_up_to_date() {
    let crate_dir = Path::new(env!("CARGO_MANIFEST_DIR"));
    let config = cbindgen::Config::from_file(crate_dir.join("cbindgen.toml"))
        .expect("crates/ffi/cbindgen.toml");
    let bindings = cbindgen::Builder::new()
        .with_src(crate_dir.join("src/lib.rs"))
        .with_config(config)
        .generate()
        .expect("cbindgen could not parse crates/ffi/src");
    let mut fresh = Vec::new();
    bindings.write(&mut fresh);
    let fresh = String::from_utf8(fresh).expect("UTF-8 header");
    let committed_path = crate_dir.join("include/admittance.h");
    if std::env::var_os("ADM_BLESS").is_some() {
        std::fs::write(&committed_path, &fresh).expect("write include/admittance.h");
        return;
    }
    let committed = std::fs::read_to_string(&committed_path).unwrap_or_default();
    if committed != fresh {
        let line = committed
            .lines()
            .zip(fresh.lines())
            .position(|(a, b)| a != b)
            .map_or(committed.lines().count().min(fresh.lines().count()), |k| k)
            + 1;
        panic!(
            "crates/ffi/include/admittance.h differs from a fresh cbindgen generation (first at \
             line {line}: committed {:?}, fresh {:?}); regenerate it with \
             `ADM_BLESS=1 cargo test -p admittance-ffi --test header` and commit it",
            committed.lines().nth(line - 1).unwrap_or("<end>"),
            fresh.lines().nth(line - 1).unwrap_or("<end>"),
        );
    }
}
