//! The Mitsuba 3 XML scene reader on any bytes: decoding, XML, parameters, properties,
//! transforms, spectra, ids and references, and printing every error; then the scene builder on
//! what reads (sensors, films, shapes, BSDFs, textures, emitters and their parameters). Relative includes and
//! `<path>` folders resolve nowhere (the text has no folder), so only absolute ones can be read
//! (bounded, regular files only, as for any scene file).
#![no_main]

use libfuzzer_sys::fuzz_target;
use raytracer::scene::SourceFile;
use raytracer::scene::mitsuba;

fuzz_target!(|bytes: &[u8]| {
    let source = SourceFile::from_bytes("fuzz.xml", None, bytes);
    let defines = [("spp".to_owned(), "4".to_owned())];
    match mitsuba::read_source(source, &defines) {
        Ok(doc) => {
            // Every reference resolves, and every position names a file that was read.
            for plugin in doc.plugins() {
                assert!((plugin.pos.file as usize) < doc.files.len());
                for child in &plugin.children {
                    assert!(doc.target(child).is_some());
                }
                for property in &plugin.properties {
                    let _ = doc.location(property.pos);
                }
            }
            // Building never panics: a scene, or errors with their places.
            match mitsuba::build(&doc) {
                Ok(built) => {
                    for p in &built.scene.primitives {
                        let _ = p.shape.bounds();
                    }
                }
                Err(errors) => assert!(errors.iter().any(|d| d.is_error())),
            }
        }
        Err(error) => {
            let _ = error.to_string();
            let _ = error.diagnostic().to_string();
        }
    }
});
