//! `bench --suite --resume`: every benched flight leaves a record in its folder
//! ([`RECORD_FILE`]: what it was run with, the device, the dataset's summary and each
//! configuration's summary). With `--resume` a flight whose record was made with the same run
//! settings, dataset and flight is taken from it instead of being flown again, so a suite cut
//! off — a time limit, a machine lent by the minute, a crash — goes on where it stopped and
//! still ends in one combined report. A record that is missing, unreadable, of another format
//! or made with other settings only means the flight runs again; the reason is printed.
//!
//! TOML rather than JSON: it keeps NaN and the infinities that summaries may hold, and Rust's
//! shortest round-trip float formatting reads back bit for bit.

use std::path::{Path, PathBuf};

use super::report::Summary;
use super::suite_config::{DatasetSpec, RunSettings, SuiteFlight};
use crate::tools::output::write_text;

/// The record's name in a flight's folder.
pub(crate) const RECORD_FILE: &str = "suite_flight.toml";

/// Bumped whenever [`FlightRecord`] or what it holds changes meaning.
const RECORD_VERSION: u32 = 1;

/// Largest record read (a flight of many configurations is a few tens of kB).
const MAX_RECORD_BYTES: u64 = 16 << 20;

/// One benched flight as the combined report needs it.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub(crate) struct FlightRecord {
    pub version: u32,
    /// What the flight was run with ([`fingerprint`]).
    pub fingerprint: String,
    /// The Vulkan device it ran on.
    pub device: String,
    /// The dataset in words (`Dataset::summary`).
    pub dataset_summary: String,
    pub summaries: Vec<Summary>,
}

impl FlightRecord {
    pub fn new(
        fingerprint: String,
        device: String,
        dataset_summary: String,
        summaries: Vec<Summary>,
    ) -> Self {
        Self {
            version: RECORD_VERSION,
            fingerprint,
            device,
            dataset_summary,
            summaries,
        }
    }
}

/// Everything a flight's results depend on: what the suite file says — its run settings, its
/// dataset and the flight itself — and what the command line says (`command_line`: the
/// bench's options that change what is drawn or measured, `BenchArgs::result_settings`), as
/// this build of aerie describes them (a build whose settings carry another field describes
/// them otherwise, and its records are not reused).
pub(crate) fn fingerprint(
    run: &RunSettings,
    dataset: &DatasetSpec,
    flight: &SuiteFlight,
    command_line: &str,
) -> String {
    format!("{run:?} / {dataset:?} / {:?} / {command_line}", flight.spec)
}

/// Whether a flight is taken from its record or flown again, and why.
#[derive(Debug)]
pub(crate) enum Resume {
    Record(Box<FlightRecord>),
    Run(String),
}

fn record_path(dir: &Path) -> PathBuf {
    dir.join(RECORD_FILE)
}

/// The record in `dir` when it was made with `fingerprint`; otherwise why not.
pub(crate) fn read_record(dir: &Path, fingerprint: &str) -> Resume {
    let path = record_path(dir);
    let name = path.display();
    let size = match std::fs::metadata(&path) {
        Ok(m) => m.len(),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            return Resume::Run(format!("{name}: no record yet"));
        }
        Err(e) => return Resume::Run(format!("{name}: {e}")),
    };
    if size > MAX_RECORD_BYTES {
        return Resume::Run(format!(
            "{name}: {size} bytes, more than a record's {MAX_RECORD_BYTES}"
        ));
    }
    let text = match std::fs::read_to_string(&path) {
        Ok(t) => t,
        Err(e) => return Resume::Run(format!("{name}: {e}")),
    };
    parse_record(&text, fingerprint).map_or_else(
        |why| Resume::Run(format!("{name}: {why}")),
        |r| Resume::Record(Box::new(r)),
    )
}

/// [`read_record`] of a record's text.
fn parse_record(text: &str, fingerprint: &str) -> Result<FlightRecord, String> {
    let record: FlightRecord = toml::from_str(text).map_err(|e| {
        let e = e.to_string();
        format!("unreadable ({})", e.lines().next().unwrap_or("").trim())
    })?;
    if record.version != RECORD_VERSION {
        return Err(format!(
            "record format {}, this build writes {RECORD_VERSION}",
            record.version
        ));
    }
    if record.fingerprint != fingerprint {
        return Err("made with other run settings, dataset or flight".into());
    }
    if record.summaries.is_empty() {
        return Err("holds no configuration".into());
    }
    Ok(record)
}

/// Writes the record into `dir` (atomically).
pub(crate) fn write_record(dir: &Path, record: &FlightRecord) -> Result<(), String> {
    let path = record_path(dir);
    let text = toml::to_string(record).map_err(|e| format!("{}: {e}", path.display()))?;
    write_text(&path, &text).map_err(|e| format!("{}: {e}", path.display()))
}

/// Removes the record from `dir` before its flight runs again, so a run that fails part-way
/// never leaves the old record beside new, partial files.
pub(crate) fn remove_record(dir: &Path) -> Result<(), String> {
    match std::fs::remove_file(record_path(dir)) {
        Ok(()) => Ok(()),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(()),
        Err(e) => Err(format!("{}: {e}", record_path(dir).display())),
    }
}

#[cfg(test)]
#[path = "suite_resume_tests.rs"]
mod tests;
