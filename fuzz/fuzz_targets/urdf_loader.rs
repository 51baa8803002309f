//! Fuzz target: any byte string given to the URDF loader either loads a model whose
//! algorithms return finite results for a zero state, or fails with an error that names
//! the source. It must never panic.
#![no_main]

use admittance_dynamics::{crba, rnea, Data, Model};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|bytes: &[u8]| {
    let Ok(text) = std::str::from_utf8(bytes) else { return };
    match Model::from_urdf_str(text, "fuzz.urdf", None, None) {
        Ok(model) => {
            let mut data = Data::new(&model);
            let zeros = vec![0.0; model.nq()];
            let _ = rnea(&model, &mut data, &zeros, &zeros, &zeros);
            let _ = crba(&model, &mut data, &zeros);
        }
        Err(e) => assert!(e.to_string().starts_with("fuzz.urdf")),
    }
});
