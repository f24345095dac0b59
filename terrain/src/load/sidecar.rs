//! The optional `<file>.json` sidecar: checked keys, typed values and the metric spacing.

use std::path::{Path, PathBuf};

use super::error::{one_line, show, DemError};

/// Default grid spacing (metres) when a file carries none and no sidecar gives one.
pub(crate) const DEFAULT_SPACING_M: f64 = 30.0;
/// Finest plausible grid spacing, metres (1 mm).
pub const MIN_SPACING_M: f64 = 1e-3;
/// Coarsest plausible grid spacing, metres (100 km).
pub const MAX_SPACING_M: f64 = 1e5;
/// Largest plausible magnitude of a height scale, metres per stored unit (a u16 then spans
/// 65 km).
pub const MAX_HEIGHT_SCALE: f64 = 1e3;
/// Largest plausible magnitude of a height offset, metres.
pub const MAX_HEIGHT_OFFSET_M: f64 = 1e5;

/// Why `spacing_m` is not a plausible grid spacing, if it is not (1 mm to 100 km).
pub(crate) fn implausible_spacing(spacing_m: f64) -> Option<String> {
    (!(MIN_SPACING_M..=MAX_SPACING_M).contains(&spacing_m)).then(|| {
        format!(
            "grid spacing {} m is outside the plausible 0.001 m (1 mm) to 100000 m (100 km)",
            short(spacing_m)
        )
    })
}

/// `v` as a short number: scientific notation where plain would be long (1e300, 1e-9).
pub(crate) fn short(v: f64) -> String {
    if v != 0.0 && !(1e-3..1e9).contains(&v.abs()) {
        format!("{v:e}")
    } else {
        format!("{v}")
    }
}

/// `<file>.json` next to `<file>` (the whole name plus `.json`, e.g. `foo.png.json`).
pub(crate) fn sidecar_path(path: &Path) -> PathBuf {
    let mut s = path.as_os_str().to_owned();
    s.push(".json");
    PathBuf::from(s)
}

/// A parsed sidecar whose keys have been checked against the loader's list.
pub(crate) struct Sidecar {
    path: PathBuf,
    map: serde_json::Map<String, serde_json::Value>,
}

impl Sidecar {
    /// Reads `<file>.json` when present. Unknown keys are rejected here so a typo
    /// (`"spacingx"`) is an error instead of a silently ignored setting.
    pub(crate) fn load(dem: &Path, allowed: &[&str]) -> Result<Option<Sidecar>, DemError> {
        let path = sidecar_path(dem);
        let bytes = match std::fs::read(&path) {
            Ok(b) => b,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
            Err(e) => {
                return Err(DemError::Sidecar {
                    path: show(&path),
                    reason: format!("cannot read sidecar: {}", one_line(&e.to_string())),
                })
            }
        };
        let value: serde_json::Value =
            serde_json::from_slice(&bytes).map_err(|e| DemError::Sidecar {
                path: show(&path),
                reason: format!("invalid JSON: {}", one_line(&e.to_string())),
            })?;
        let serde_json::Value::Object(map) = value else {
            return Err(DemError::Sidecar {
                path: show(&path),
                reason: format!("expected a JSON object, found {}", json_type(&value)),
            });
        };
        for key in map.keys() {
            if !allowed.contains(&key.as_str()) {
                return Err(DemError::Sidecar {
                    path: show(&path),
                    reason: format!(
                        "unknown key `{}` (accepted: {})",
                        one_line(key),
                        allowed.join(", ")
                    ),
                });
            }
        }
        Ok(Some(Sidecar { path, map }))
    }

    /// Like [`Sidecar::load`], for formats that cannot be read without one.
    pub(crate) fn require(dem: &Path, allowed: &[&str], needs: &str) -> Result<Sidecar, DemError> {
        Self::load(dem, allowed)?.ok_or_else(|| DemError::Sidecar {
            path: show(dem),
            reason: format!(
                "missing sidecar {} (a JSON object with {needs})",
                show(&sidecar_path(dem))
            ),
        })
    }

    pub(crate) fn path(&self) -> &Path {
        &self.path
    }

    pub(crate) fn err(&self, key: &str, reason: impl std::fmt::Display) -> DemError {
        DemError::Sidecar {
            path: show(&self.path),
            reason: one_line(&format!("key `{key}`: {reason}")),
        }
    }

    fn wrong_type(&self, key: &str, want: &str, v: &serde_json::Value) -> DemError {
        self.err(key, format!("expected {want}, found {}", json_type(v)))
    }

    /// A finite number.
    pub(crate) fn f64(&self, key: &str) -> Result<Option<f64>, DemError> {
        match self.map.get(key) {
            None => Ok(None),
            Some(v) => match v.as_f64() {
                Some(x) if x.is_finite() => Ok(Some(x)),
                _ => Err(self.wrong_type(key, "a finite number", v)),
            },
        }
    }

    /// A grid spacing in metres: a finite number from 1 mm to 100 km.
    pub(crate) fn spacing(&self, key: &str) -> Result<Option<f64>, DemError> {
        match self.f64(key)? {
            Some(x) if x <= 0.0 => Err(self.err(key, format!("must be > 0, found {x}"))),
            Some(x) => match implausible_spacing(x) {
                Some(why) => Err(self.err(key, why)),
                None => Ok(Some(x)),
            },
            None => Ok(None),
        }
    }

    /// A height `scale` (metres per stored unit) and `offset` (metres): finite, non-zero scale,
    /// magnitudes at most [`MAX_HEIGHT_SCALE`] and [`MAX_HEIGHT_OFFSET_M`]; defaults 1 and 0.
    pub(crate) fn height_scale_offset(&self) -> Result<(f64, f64), DemError> {
        let scale = self.f64("scale")?.unwrap_or(1.0);
        if scale == 0.0 || scale.abs() > MAX_HEIGHT_SCALE {
            return Err(self.err(
                "scale",
                format!("{} is not a plausible height scale (non-zero, within ±{MAX_HEIGHT_SCALE} m per unit)", short(scale)),
            ));
        }
        let offset = self.f64("offset")?.unwrap_or(0.0);
        if offset.abs() > MAX_HEIGHT_OFFSET_M {
            return Err(self.err(
                "offset",
                format!(
                    "{offset} m is not a plausible height offset (within ±{MAX_HEIGHT_OFFSET_M} m)"
                ),
            ));
        }
        Ok((scale, offset))
    }

    pub(crate) fn bool(&self, key: &str) -> Result<Option<bool>, DemError> {
        match self.map.get(key) {
            None => Ok(None),
            Some(serde_json::Value::Bool(b)) => Ok(Some(*b)),
            Some(v) => Err(self.wrong_type(key, "true or false", v)),
        }
    }

    /// A non-negative integer that fits in `usize`.
    pub(crate) fn usize(&self, key: &str) -> Result<Option<usize>, DemError> {
        match self.map.get(key) {
            None => Ok(None),
            Some(v) => match v.as_u64().and_then(|x| usize::try_from(x).ok()) {
                Some(x) => Ok(Some(x)),
                None => Err(self.wrong_type(key, "a non-negative integer", v)),
            },
        }
    }

    pub(crate) fn str(&self, key: &str) -> Result<Option<&str>, DemError> {
        match self.map.get(key) {
            None => Ok(None),
            Some(serde_json::Value::String(s)) => Ok(Some(s)),
            Some(v) => Err(self.wrong_type(key, "a string", v)),
        }
    }
}

fn json_type(v: &serde_json::Value) -> String {
    match v {
        serde_json::Value::Null => "null".into(),
        serde_json::Value::Bool(b) => format!("boolean {b}"),
        serde_json::Value::Number(n) => format!("number {n}"),
        serde_json::Value::String(_) => "a string".into(),
        serde_json::Value::Array(_) => "an array".into(),
        serde_json::Value::Object(_) => "an object".into(),
    }
}

/// Spacing for grids without a geo-reference: sidecar values or the 30 m default, plus the
/// sentence for `spacing_note`.
pub(crate) fn metric_spacing(sidecar: Option<&Sidecar>) -> Result<(f64, f64, String), DemError> {
    let sx = match sidecar {
        Some(s) => s.spacing("spacing_x")?,
        None => None,
    };
    let sy = match sidecar {
        Some(s) => s.spacing("spacing_y")?,
        None => None,
    };
    let note = match (sidecar, sx, sy) {
        (Some(s), Some(x), Some(y)) => format!(
            "from sidecar {}: {x} m E-W, {y} m N-S",
            show(s.path())
        ),
        (Some(s), x, y) if x.is_some() || y.is_some() => format!(
            "from sidecar {} with the {DEFAULT_SPACING_M} m default for the missing one: {} m E-W, {} m N-S",
            show(s.path()),
            x.unwrap_or(DEFAULT_SPACING_M),
            y.unwrap_or(DEFAULT_SPACING_M)
        ),
        _ => format!(
            "default {DEFAULT_SPACING_M} m grid (no spacing in the file or a sidecar): {DEFAULT_SPACING_M} m E-W, {DEFAULT_SPACING_M} m N-S"
        ),
    };
    Ok((
        sx.unwrap_or(DEFAULT_SPACING_M),
        sy.unwrap_or(DEFAULT_SPACING_M),
        note,
    ))
}
