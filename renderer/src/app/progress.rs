//! Progress on stderr and sizes for people: the common bar styles and byte counts.

/// A progress bar over samples with the common style (hidden when stderr is not a terminal).
pub fn progress_bar(len: u64, what: &str) -> indicatif::ProgressBar {
    styled_bar(
        len,
        "{msg} [{bar:30}] {percent:>3}% {human_pos}/{human_len} samples, eta {eta}",
        what,
    )
}

/// A progress bar over `len` items counted as `unit` ("frames", "renders").
pub fn count_bar(len: u64, unit: &str, what: &str) -> indicatif::ProgressBar {
    styled_bar(
        len,
        &format!("{{msg}} [{{bar:30}}] {{pos}}/{{len}} {unit}, eta {{eta}}"),
        what,
    )
}

fn styled_bar(len: u64, template: &str, what: &str) -> indicatif::ProgressBar {
    let bar = indicatif::ProgressBar::new(len);
    bar.set_style(
        indicatif::ProgressStyle::with_template(template)
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );
    bar.set_message(what.to_string());
    bar
}

/// "1.23 MB", "845 kB", "1.07 GB".
pub fn human_bytes(n: u64) -> String {
    let n = n as f64;
    if n >= 1e9 {
        format!("{:.2} GB", n / 1e9)
    } else if n >= 1e6 {
        format!("{:.2} MB", n / 1e6)
    } else if n >= 1e3 {
        format!("{:.1} kB", n / 1e3)
    } else {
        format!("{n} B")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bytes_read_as_people_write_them() {
        assert_eq!(human_bytes(512), "512 B");
        assert_eq!(human_bytes(845_000), "845.0 kB");
        assert_eq!(human_bytes(1_234_567), "1.23 MB");
        assert_eq!(human_bytes(1_070_000_000), "1.07 GB");
    }
}
