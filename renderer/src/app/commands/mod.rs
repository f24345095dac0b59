//! Offline data commands: `aerie gen-dem` (synthetic terrains) and `aerie bake` (the error bake).
//! Each returns the CLI's [`Failure`](crate::app::failure::Failure): exit 2 for bad input, 1 at run time.

pub mod bake;
pub mod bench;
pub mod fly;
pub mod gen_dem;
pub mod input_args;
pub mod listen;
pub mod replay;
pub mod run;

/// A progress bar on stderr with the common style (hidden when stderr is not a terminal).
pub(crate) fn progress_bar(len: u64, what: &str) -> indicatif::ProgressBar {
    let bar = indicatif::ProgressBar::new(len);
    bar.set_style(
        indicatif::ProgressStyle::with_template(
            "{msg} [{bar:30}] {percent:>3}% {human_pos}/{human_len} samples, eta {eta}",
        )
        .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );
    bar.set_message(what.to_string());
    bar
}

/// "1.23 MB", "845 kB", "1.07 GB".
pub(crate) fn human_bytes(n: u64) -> String {
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

/// Refuses an output path whose folder does not exist.
pub(crate) fn check_out_folder(
    flag: &str,
    out: &std::path::Path,
) -> Result<(), crate::app::failure::Failure> {
    let parent = out.parent().filter(|p| !p.as_os_str().is_empty());
    if let Some(p) = parent {
        if !p.is_dir() {
            return Err(crate::app::failure::bad_input(format!(
                "{flag} {}: folder {} does not exist",
                out.display(),
                p.display()
            )));
        }
    }
    if out.is_dir() {
        return Err(crate::app::failure::bad_input(format!(
            "{flag} {}: is a folder, expected a file name",
            out.display()
        )));
    }
    Ok(())
}
