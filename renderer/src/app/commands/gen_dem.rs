//! `aerie gen-dem`: writes a deterministic synthetic terrain ([`aerie_terrain::gen`]) as raw
//! little-endian f32 plus the JSON sidecar the raw loader reads (`<out>.json`), so the result
//! loads with `--dem <out>` / `aerie bake <out>` like any other DEM. Rows are south first
//! (`"north_up": false`). The rows are generated a band at a time by all cores and written
//! as each band completes, so memory holds one band (≤ 32 MiB), not the grid, whatever its
//! size; the file is renamed into place when complete ([`aerie_io::AtomicFile`]); on any
//! failure no temporary is left.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::Instant;

use clap::Args;

use crate::app::failure::{bad_input, runtime, Failure};
use crate::app::out_path::{prepare_out_file, with_suffix};
use crate::app::progress::{human_bytes, progress_bar};
use aerie_terrain::gen::{generate_into, DemKind, GenParams};

/// Largest side accepted (32769² f32 = 4.3 GB).
const MAX_SIZE: usize = 32769;

#[derive(Debug, Args)]
pub struct GenDemArgs {
    /// Samples per side of the square grid (16385 = 2^14 + 1 is Puget-Sound size).
    #[arg(long, default_value_t = 4097)]
    pub size: usize,
    /// Metres between samples.
    #[arg(long, default_value_t = 10.0)]
    pub spacing: f64,
    /// ridged (mountains), cliffs (terraces with vertical walls), spikes (single-sample
    /// needles), flat, or mixed (one quadrant of each).
    #[arg(long, default_value = "mixed", value_parser = ["ridged", "cliffs", "spikes", "flat", "mixed"])]
    pub kind: String,
    /// Seed: the same seed (and size, spacing, kind) always gives the same bytes.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Output raw f32 file (.f32, .r32 or .raw; its folder is created); the sidecar `<out>.json`
    /// is written next to it.
    #[arg(long)]
    pub out: PathBuf,
}

/// Rows per band: about 8 Mi samples (32 MiB as f32), at least one row.
fn band_rows(size: usize) -> usize {
    ((8 << 20) / size).clamp(1, size)
}

/// The sidecar path the raw loader looks for.
fn sidecar(out: &Path) -> PathBuf {
    with_suffix(out, ".json")
}

pub fn run(a: GenDemArgs) -> Result<(), Failure> {
    let kind = DemKind::parse(&a.kind).ok_or_else(|| {
        bad_input(format!(
            "--kind: `{}` is not one of ridged, cliffs, spikes, flat, mixed",
            a.kind
        ))
    })?;
    if !(2..=MAX_SIZE).contains(&a.size) {
        return Err(bad_input(format!(
            "--size: {} is outside 2..={MAX_SIZE} samples per side",
            a.size
        )));
    }
    if !(a.spacing.is_finite() && a.spacing > 0.0) {
        return Err(bad_input(format!(
            "--spacing: {} must be a finite number of metres > 0",
            a.spacing
        )));
    }
    let name = a
        .out
        .file_name()
        .map(|n| n.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default();
    if ![".f32", ".r32", ".raw"].iter().any(|e| name.ends_with(e)) {
        return Err(bad_input(format!(
            "--out {}: use a .f32, .r32 or .raw name (raw little-endian f32 with a JSON sidecar)",
            a.out.display()
        )));
    }
    prepare_out_file("--out", &a.out)?;
    let p = GenParams {
        size: a.size,
        spacing: a.spacing,
        kind,
        seed: a.seed,
    };
    let n = a.size;
    let samples = (n * n) as u64;
    let bytes = samples * 4;
    let t = Instant::now();
    let bar = progress_bar(samples, &format!("generating {} {n}×{n}", kind.name()));
    let result = (|| -> Result<(f32, f32), aerie_io::WriteError> {
        let mut file = aerie_io::AtomicFile::create(&a.out)?;
        let band_rows = band_rows(n);
        let mut band = vec![0f32; band_rows * n];
        let mut bytes_out: Vec<u8> = Vec::with_capacity(band.len() * 4);
        let (mut lo, mut hi) = (f32::INFINITY, f32::NEG_INFINITY);
        for row0 in (0..n).step_by(band_rows) {
            let rows = band_rows.min(n - row0);
            let heights = &mut band[..rows * n];
            generate_into(&p, row0, heights, &|r| {
                bar.set_position((row0 as u64 + r) * n as u64)
            });
            bytes_out.clear();
            for &v in heights.iter() {
                lo = lo.min(v);
                hi = hi.max(v);
                bytes_out.extend_from_slice(&v.to_le_bytes());
            }
            file.write_all(&bytes_out)
                .map_err(|source| aerie_io::WriteError {
                    path: a.out.clone(),
                    step: "write",
                    source,
                })?;
        }
        file.commit()?;
        Ok((lo, hi))
    })();
    bar.finish_and_clear();
    let (lo, hi) = result.map_err(runtime)?;
    let json = serde_json::json!({
        "width": n,
        "height": n,
        "format": "f32le",
        "spacing_x": a.spacing,
        "spacing_y": a.spacing,
        "north_up": false,
        "generator": {
            "program": format!("aerie {}", env!("CARGO_PKG_VERSION")),
            "kind": kind.name(),
            "seed": a.seed,
        },
    });
    let side = sidecar(&a.out);
    aerie_io::write_atomic(&side, format!("{json:#}\n").as_bytes()).map_err(runtime)?;
    let secs = t.elapsed().as_secs_f64();
    println!(
        "generated {}: {n}×{n} {} (seed {}), {} m spacing, {lo:.1}..{hi:.1} m, {} in {secs:.2} s ({:.1} M samples/s); sidecar {}",
        a.out.display(),
        kind.name(),
        a.seed,
        a.spacing,
        human_bytes(bytes),
        samples as f64 / secs / 1e6,
        side.display()
    );
    Ok(())
}
