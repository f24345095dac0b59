//! Every preset in `config/presets/` must parse and validate.

use std::path::Path;

#[test]
fn every_preset_validates() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("presets");
    let mut count = 0;
    for entry in std::fs::read_dir(&dir).expect("config/presets exists") {
        let path = entry.unwrap().path();
        if path.extension().is_some_and(|e| e == "toml") {
            if let Err(e) = aerie_config::load(&path) {
                panic!("{e}");
            }
            count += 1;
        }
    }
    assert!(count >= 1, "no presets in {}", dir.display());
}

#[test]
fn ci_headless_preset_is_small_and_validated() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("presets/ci-headless.toml");
    let cfg = aerie_config::load(path).unwrap();
    assert_eq!((cfg.render.width, cfg.render.height), (320, 180));
    assert_eq!(cfg.render.fov_deg, 90.0);
    assert!(cfg.render.validation);
}
