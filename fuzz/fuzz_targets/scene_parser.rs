//! The scene parser on any bytes: decoding (UTF-8 or GBK), parsing, and printing every
//! diagnostic (the excerpt code must stay in bounds and linear on any line).
#![no_main]

use libfuzzer_sys::fuzz_target;
use raytracer::scene::{self, SourceFile};

fuzz_target!(|bytes: &[u8]| {
    let source = SourceFile::from_bytes("fuzz.txt", None, bytes);
    match scene::parse(&source) {
        Ok(parsed) => {
            for d in &parsed.diagnostics {
                let _ = d.to_string();
            }
        }
        Err(error) => {
            assert!(error.error_count() > 0);
            let _ = error.to_string();
        }
    }
});
