//! `WIDTHxHEIGHT` sizes, as written in config files and on the command line.

/// Largest accepted viewport width or height, pixels.
pub const MAX_DIMENSION: u32 = 16384;

/// Parses `WIDTHxHEIGHT` (`x` or `X`, e.g. `1920x1080`; whitespace around the whole is
/// ignored) into `(width, height)`, each 1..=[`MAX_DIMENSION`] pixels. The error is one line
/// that quotes the input.
pub fn parse_size(s: &str) -> Result<(u32, u32), String> {
    let malformed = || format!("expected \"WIDTHxHEIGHT\" such as \"1920x1080\", got {s:?}");
    let (w, h) = s.trim().split_once(['x', 'X']).ok_or_else(malformed)?;
    let digits = |t: &str| !t.is_empty() && t.bytes().all(|b| b.is_ascii_digit());
    if !digits(w) || !digits(h) {
        return Err(malformed());
    }
    let dim = |t: &str| {
        t.parse::<u64>()
            .ok()
            .filter(|v| (1..=u64::from(MAX_DIMENSION)).contains(v))
    };
    match (dim(w), dim(h)) {
        (Some(w), Some(h)) => Ok((w as u32, h as u32)),
        _ => Err(format!(
            "width and height must each be 1..={MAX_DIMENSION} pixels, got {s:?}"
        )),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn accepts_both_separators_and_the_whole_range() {
        assert_eq!(parse_size("1920x1080"), Ok((1920, 1080)));
        assert_eq!(parse_size("640X480"), Ok((640, 480)));
        assert_eq!(parse_size("1x16384"), Ok((1, 16384)));
        assert_eq!(parse_size("16384x1"), Ok((16384, 1)));
        assert_eq!(parse_size("  800x600\n"), Ok((800, 600)));
        assert_eq!(parse_size("0007x0009"), Ok((7, 9)));
    }

    #[test]
    fn rejects_bad_shapes_with_the_expected_form() {
        for input in [
            "", "1920", "x1080", "1920x", "axb", "10x-5", "-10x5", "+10x5", "10 x 5", "1.5x2",
            "1x2x3",
        ] {
            let e = parse_size(input).unwrap_err();
            assert!(e.contains("expected \"WIDTHxHEIGHT\""), "{input:?}: {e}");
            assert!(e.contains(&format!("{input:?}")), "{input:?}: {e}");
            assert!(!e.contains('\n'), "{e}");
        }
    }

    #[test]
    fn rejects_sides_out_of_range() {
        for input in [
            "0x10",
            "10x0",
            "16385x10",
            "10x16385",
            "99999999999999999999x10",
        ] {
            let e = parse_size(input).unwrap_err();
            assert!(
                e.contains("must each be 1..=16384 pixels"),
                "{input:?}: {e}"
            );
            assert!(e.contains(&format!("{input:?}")), "{input:?}: {e}");
        }
    }
}
