//! Limits on a configuration: its size and its channel count. A config is refused with an
//! error naming the limit before it can exhaust memory or make a frame cost minutes.

use aerie_config::{load, parse, ConfigError, MAX_CHANNELS, MAX_CONFIG_BYTES};

fn channels(n: usize) -> String {
    let mut s = String::from("[render]\nsize = \"64x48\"\n");
    for i in 0..n {
        s.push_str(&format!(
            "[[channel]]\nname = \"c{i}\"\nview = {{ heading = {} }}\n",
            (i % 360) as f64 - 180.0
        ));
    }
    s
}

#[test]
fn sixty_four_channels_are_accepted() {
    let cfg = parse(&channels(MAX_CHANNELS), "wall.toml").unwrap();
    assert_eq!(cfg.channels.len(), MAX_CHANNELS);
}

#[test]
fn a_ten_thousand_channel_config_is_refused() {
    let e = parse(&channels(10_000), "wall.toml").unwrap_err();
    let msg = e.to_string();
    assert_eq!(e.key(), Some("channel"), "{msg}");
    assert!(msg.starts_with("wall.toml"), "{msg}");
    assert!(
        msg.contains("10000") && msg.contains("limit of 64"),
        "{msg}"
    );
    let e = parse(&channels(MAX_CHANNELS + 1), "wall.toml").unwrap_err();
    assert!(e.to_string().contains("65 [[channel]]"), "{e}");
}

#[test]
fn a_two_mib_config_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("big.toml");
    // Valid TOML all the way: a comment padded to 2 MiB.
    let mut text = String::from("[render]\n#");
    text.push_str(&"x".repeat(2 << 20));
    text.push('\n');
    std::fs::write(&path, &text).unwrap();
    let e = load(&path).unwrap_err();
    let msg = e.to_string();
    assert!(matches!(e, ConfigError::TooLarge { .. }), "{msg}");
    assert!(msg.contains("big.toml"), "{msg}");
    assert!(msg.contains("1024 KiB limit"), "{msg}");
    assert!(msg.contains(&format!("{} bytes", text.len())), "{msg}");
    // The same text handed to `parse` is refused too.
    assert!(matches!(
        parse(&text, "big.toml"),
        Err(ConfigError::TooLarge { .. })
    ));
    // Exactly at the limit is read (and then judged as TOML).
    let mut at = String::from("#");
    at.push_str(&"x".repeat(MAX_CONFIG_BYTES as usize - 2));
    at.push('\n');
    assert_eq!(at.len() as u64, MAX_CONFIG_BYTES);
    std::fs::write(&path, &at).unwrap();
    load(&path).unwrap();
}

#[test]
fn dev_zero_is_refused_after_reading_at_most_the_limit() {
    // A character device reports length 0: the read itself is bounded.
    let e = load("/dev/zero").unwrap_err();
    let msg = e.to_string();
    assert!(
        matches!(e, ConfigError::TooLarge { size: None, .. }),
        "{msg}"
    );
    assert!(msg.starts_with("/dev/zero"), "{msg}");
}

#[test]
fn binary_is_refused_naming_the_offset() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("bin.toml");
    std::fs::write(&path, b"[render]\n\xff\xfe").unwrap();
    let msg = load(&path).unwrap_err().to_string();
    assert!(
        msg.contains("bin.toml") && msg.contains("offset 9"),
        "{msg}"
    );
}
