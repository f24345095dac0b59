//! Typed, validated configuration for aerie.
//!
//! A config file is TOML with a `[render]` and an optional `[dem]` table; every key is optional
//! and unknown keys are errors. [`load`] and [`parse`] return a [`RenderConfig`] whose values are
//! all within range, or a [`ConfigError`] whose message is one line naming the file, the key
//! (dotted, e.g. `render.tile_size`), the line and column when known, and the reason:
//!
//! ```text
//! site.toml:4:13: render.tile_size: must be 2^j+1 between 3 and 257 (3, 5, 9, 17, 33, 65, 129, 257), got 16
//! ```
//!
//! ```toml
//! [render]
//! size = "1920x1080"        # or: width = 1920, height = 1080
//! fov_deg = 90.0            # horizontal field of view, degrees, (0, 180)
//! tau_px = 1.0              # screen-space error bound τ, pixels, > 0
//! tile_size = 17            # vertices per tile side m = 2^j+1, 3..=257
//! staging_budget_mib = 8    # upload budget per frame, MiB, 1..=1024
//! validation = false        # enable VK_LAYER_KHRONOS_validation
//! gpu = "RTX"               # optional: pick the first GPU whose name contains this
//! fps = 60.0                # optional: `aerie run --headless` pacing, frames/s, (0, 1000]
//!
//! [input]                   # optional: simulator pose input of `aerie run` (see [`InputSettings`])
//! protocol = "cigi"
//!
//! [dem]
//! path = "data/dem.tif"     # optional: elevation dataset
//!
//! [[channel]]               # optional, repeated: display channels (see [`Channel`])
//! name = "centre"
//!
//! [databases]               # optional: CIGI database number → dataset (see [`Databases`])
//! 1 = "dem/N47E011.hgt.zip"
//!
//! [landcover]               # optional: land-cover codes (see [`landcover`])
//! raster = "worldcover.tif" # optional, relative to the config's folder
//! preset = "worldcover"
//! ```

mod channels;
mod databases;
pub mod entities;
mod error;
mod input;
pub mod landcover;
mod limits;
mod locate;
mod path_de;
mod settings;
mod size;

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

pub use channels::{
    Channel, ChannelDisplay, ChannelFrustum, EyeOffset, FullscreenMode, MonitorSelector,
    PresentMode, ViewOffset,
};
pub use databases::{Databases, MAX_DATABASE};
pub use entities::EntitySettings;
pub use error::{ConfigError, Location};
pub use input::{
    HostHeightsName, InputProtocolName, InputSettings, MAX_SYNC_FRAMES, MAX_WORLD_BOUND_M,
};
pub use landcover::LandcoverSettings;
pub use limits::{MAX_CHANNELS, MAX_CONFIG_BYTES};
pub use locate::key_location;
pub use settings::{
    is_valid_tile_size, DemSettings, RenderSettings, MAX_STAGING_BUDGET_MIB, TILE_SIZES,
};
pub use size::{parse_size, MAX_DIMENSION};

/// The whole configuration file, validated.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct RenderConfig {
    /// The `[render]` table.
    pub render: RenderSettings,
    /// The `[dem]` table.
    pub dem: DemSettings,
    /// The `[input]` table (every key optional: command-line flags and defaults fill the rest).
    #[serde(skip_serializing_if = "InputSettings::is_empty")]
    pub input: InputSettings,
    /// The `[[channel]]` tables, in file order (empty: none configured).
    #[serde(rename = "channel", skip_serializing_if = "Vec::is_empty")]
    pub channels: Vec<Channel>,
    /// The `[databases]` table: CIGI database number → dataset.
    #[serde(skip_serializing_if = "Databases::is_empty")]
    pub databases: Databases,
    /// The `[entities]` table: models of the host's other entities and their LOD.
    #[serde(skip_serializing_if = "EntitySettings::is_default")]
    pub entities: EntitySettings,
    /// The `[landcover]` table: the land-cover raster's code mapping (and the raster).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub landcover: Option<LandcoverSettings>,
}

impl RenderConfig {
    /// Writes the configuration as TOML that [`parse`] reads back to an equal value
    /// (the size is written as `width` and `height`).
    pub fn to_toml(&self) -> Result<String, toml::ser::Error> {
        toml::to_string(self)
    }
}

/// Reads and validates the config file at `path`; errors name `path`. Reads at most
/// [`MAX_CONFIG_BYTES`] + 1 bytes, so a device or pipe (`/dev/zero`) is refused, not slurped.
pub fn load(path: impl AsRef<Path>) -> Result<RenderConfig, ConfigError> {
    use std::io::Read;
    let path = path.as_ref();
    let io = |source| ConfigError::Io {
        path: path.to_path_buf(),
        source,
    };
    let too_large = |size| ConfigError::TooLarge {
        source_name: path.display().to_string(),
        size,
    };
    let file = std::fs::File::open(path).map_err(io)?;
    if let Ok(m) = file.metadata() {
        if m.is_file() && m.len() > MAX_CONFIG_BYTES {
            return Err(too_large(Some(m.len())));
        }
    }
    let mut bytes = Vec::new();
    file.take(MAX_CONFIG_BYTES + 1)
        .read_to_end(&mut bytes)
        .map_err(io)?;
    if bytes.len() as u64 > MAX_CONFIG_BYTES {
        return Err(too_large(None));
    }
    let text = String::from_utf8(bytes).map_err(|e| {
        io(std::io::Error::new(
            std::io::ErrorKind::InvalidData,
            format!(
                "not UTF-8 text (invalid byte at offset {})",
                e.utf8_error().valid_up_to()
            ),
        ))
    })?;
    parse(&text, &path.display().to_string())
}

/// Parses and validates config `text`; `source_name` (usually the file name) starts every
/// error message.
pub fn parse(text: &str, source_name: &str) -> Result<RenderConfig, ConfigError> {
    if text.len() as u64 > MAX_CONFIG_BYTES {
        return Err(ConfigError::TooLarge {
            source_name: source_name.to_owned(),
            size: Some(text.len() as u64),
        });
    }
    // 1. TOML syntax.
    let table: toml::Table = toml::from_str(text).map_err(|e| ConfigError::Syntax {
        source_name: source_name.to_owned(),
        location: e
            .span()
            .map(|s| Location::from_offset(text, s.start))
            .unwrap_or(Location { line: 1, column: 1 }),
        message: error::one_line(e.message()),
    })?;

    // 2. Shape and types (unknown keys, wrong types), with the key path of the first error.
    let root = toml::Value::Table(table);
    let raw: RawConfig = path_de::from_value(&root).map_err(|e| {
        let message = error::one_line(&e.message);
        // toml's own deserializer knows the span; use it when it reports the same problem.
        let location = match toml::from_str::<RawConfig>(text) {
            Err(te) if error::one_line(te.message()) == message => {
                te.span().map(|s| Location::from_offset(text, s.start))
            }
            _ => None,
        };
        ConfigError::Invalid {
            source_name: source_name.to_owned(),
            key: path_de::dotted(e.path.as_deref().unwrap_or(&[])),
            location,
            message,
        }
    })?;

    // 3. Ranges and cross-key rules.
    let mut raw = raw;
    let raw_channels = std::mem::take(&mut raw.channel);
    let raw_databases = std::mem::take(&mut raw.databases);
    let raw_entities = std::mem::take(&mut raw.entities);
    let raw_landcover = raw.landcover.take();
    if raw_channels.len() > MAX_CHANNELS {
        return Err(ConfigError::Invalid {
            source_name: source_name.to_owned(),
            location: locate::key_location(text, "channel"),
            key: "channel".to_owned(),
            message: format!(
                "{} [[channel]] tables, more than the limit of {MAX_CHANNELS}",
                raw_channels.len()
            ),
        });
    }
    let mut cfg = raw
        .validate()
        .map_err(|(key, message)| ConfigError::Invalid {
            source_name: source_name.to_owned(),
            location: locate::key_location(text, key),
            key: key.to_owned(),
            message,
        })?;
    cfg.channels =
        channels::validate(raw_channels, &cfg.render).map_err(|e| ConfigError::Invalid {
            source_name: source_name.to_owned(),
            location: locate::locate(text, &e.path),
            key: e.dotted(),
            message: e.message,
        })?;
    // A table's own check names its key (dotted) and the reason; the text gives the place.
    let invalid = |(key, message): (String, String)| ConfigError::Invalid {
        source_name: source_name.to_owned(),
        location: locate::key_location(text, &key),
        key,
        message,
    };
    cfg.databases = databases::validate(raw_databases).map_err(invalid)?;
    cfg.entities = raw_entities.validate().map_err(invalid)?;
    cfg.landcover = raw_landcover
        .map(landcover::RawLandcover::validate)
        .transpose()
        .map_err(invalid)?;
    Ok(cfg)
}

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields, expecting = "a table")]
struct RawConfig {
    #[serde(default)]
    render: RawRender,
    #[serde(default)]
    dem: RawDem,
    #[serde(default)]
    input: input::RawInput,
    #[serde(default)]
    channel: Vec<channels::RawChannel>,
    #[serde(default)]
    databases: std::collections::BTreeMap<String, PathBuf>,
    #[serde(default)]
    entities: entities::RawEntities,
    landcover: Option<landcover::RawLandcover>,
}

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields, expecting = "a table of render settings")]
struct RawRender {
    size: Option<String>,
    width: Option<u32>,
    height: Option<u32>,
    fov_deg: Option<f64>,
    tau_px: Option<f64>,
    tile_size: Option<u32>,
    staging_budget_mib: Option<u32>,
    validation: Option<bool>,
    gpu: Option<String>,
    fps: Option<f64>,
}

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields, expecting = "a table of DEM settings")]
struct RawDem {
    path: Option<PathBuf>,
}

/// A validation failure: the dotted key and the reason.
type Invalid = (&'static str, String);

fn check_dimension(key: &'static str, v: u32) -> Result<u32, Invalid> {
    if (1..=MAX_DIMENSION).contains(&v) {
        Ok(v)
    } else {
        Err((key, format!("must be 1..={MAX_DIMENSION} pixels, got {v}")))
    }
}

impl RawConfig {
    fn validate(self) -> Result<RenderConfig, Invalid> {
        let d = RenderSettings::default();
        let r = self.render;

        let (width, height) = match (r.size.as_deref(), r.width, r.height) {
            (Some(_), Some(_), _) | (Some(_), _, Some(_)) => {
                return Err((
                    "render.size",
                    "give either size or width and height, not both".to_owned(),
                ))
            }
            (Some(s), None, None) => parse_size(s).map_err(|m| ("render.size", m))?,
            (None, Some(w), Some(h)) => (
                check_dimension("render.width", w)?,
                check_dimension("render.height", h)?,
            ),
            (None, Some(_), None) => {
                return Err((
                    "render.height",
                    "missing: width and height go together (or use size = \"WxH\")".to_owned(),
                ))
            }
            (None, None, Some(_)) => {
                return Err((
                    "render.width",
                    "missing: width and height go together (or use size = \"WxH\")".to_owned(),
                ))
            }
            (None, None, None) => (d.width, d.height),
        };

        let fov_deg = r.fov_deg.unwrap_or(d.fov_deg);
        if !(fov_deg > 0.0 && fov_deg < 180.0) {
            return Err((
                "render.fov_deg",
                format!("must be greater than 0 and less than 180 degrees, got {fov_deg}"),
            ));
        }

        let tau_px = r.tau_px.unwrap_or(d.tau_px);
        if !(tau_px.is_finite() && tau_px > 0.0) {
            return Err((
                "render.tau_px",
                format!("must be a finite number of pixels greater than 0, got {tau_px}"),
            ));
        }

        let tile_size = r.tile_size.unwrap_or(d.tile_size);
        if !is_valid_tile_size(tile_size) {
            let list = TILE_SIZES.map(|m| m.to_string()).join(", ");
            return Err((
                "render.tile_size",
                format!("must be 2^j+1 between 3 and 257 ({list}), got {tile_size}"),
            ));
        }

        let staging_budget_mib = r.staging_budget_mib.unwrap_or(d.staging_budget_mib);
        if !(1..=MAX_STAGING_BUDGET_MIB).contains(&staging_budget_mib) {
            return Err((
                "render.staging_budget_mib",
                format!("must be 1..={MAX_STAGING_BUDGET_MIB} MiB, got {staging_budget_mib}"),
            ));
        }

        if r.gpu.as_deref().is_some_and(|g| g.trim().is_empty()) {
            return Err((
                "render.gpu",
                "must not be empty (omit the key to let aerie choose the GPU)".to_owned(),
            ));
        }

        if let Some(fps) = r.fps {
            if !(fps.is_finite() && fps > 0.0 && fps <= 1000.0) {
                return Err((
                    "render.fps",
                    format!("must be greater than 0 and at most 1000 frames per second, got {fps}"),
                ));
            }
        }

        let input = self.input.validate()?;

        if self
            .dem
            .path
            .as_deref()
            .is_some_and(|p| p.as_os_str().is_empty())
        {
            return Err(("dem.path", "must not be empty".to_owned()));
        }

        Ok(RenderConfig {
            render: RenderSettings {
                width,
                height,
                fov_deg,
                tau_px,
                tile_size,
                staging_budget_mib,
                validation: r.validation.unwrap_or(d.validation),
                gpu: r.gpu,
                fps: r.fps,
            },
            dem: DemSettings {
                path: self.dem.path,
            },
            input,
            channels: Vec::new(),
            databases: Databases::default(),
            entities: EntitySettings::default(),
            landcover: None,
        })
    }
}

#[cfg(test)]
mod tests;
