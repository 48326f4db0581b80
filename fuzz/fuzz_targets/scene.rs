//! libFuzzer target: the scene loader (`Scene::from_toml`, parse + validation) on arbitrary text.
//! It must never panic and every error must be one line (the CLI prints it as one).
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    // Scene files are read as UTF-8 text; other bytes are refused before the loader sees them.
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    if let Err(e) = <sdcrack_core::scene::Scene as sdcrack_io::scene_file::TomlScene>::from_toml(text) {
        let message = e.to_string();
        assert!(
            !message.contains('\n') && !message.contains('\r'),
            "multi-line error: {message:?}"
        );
    }
});
