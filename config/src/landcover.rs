//! The land-cover mapping: which of aerie's 8 classes each code of a land-cover raster
//! (`--landcover <GeoTIFF of class codes>`) stands for. A `[landcover]` table names a built-in
//! preset and/or lists codes; codes listed override the preset's.
//!
//! ```toml
//! [landcover]
//! preset = "worldcover"     # or "corine"; optional
//!
//! [landcover.codes]         # raster code (0..=254) → class
//! 10 = "forest"             # water, sand, grass, crops, forest, rock, snow, urban
//! 95 = "none"               # "none": drawn with the derived classes
//! ```
//!
//! Presets:
//! - **worldcover** (ESA WorldCover 10 m, v100/v200): 10 tree cover → forest, 20 shrubland → grass,
//!   30 grassland → grass, 40 cropland → crops, 50 built-up → urban, 60 bare / sparse
//!   vegetation → sand, 70 snow and ice → snow, 80 permanent water → water, 90 herbaceous
//!   wetland → grass, 95 mangroves → forest, 100 moss and lichen → grass; 0 (no data) → none.
//! - **corine** (CORINE Land Cover raster, the grid codes 1–44 of its 100 m GeoTIFF; the
//!   three-digit CLC codes do not fit a byte): 1–6, 9 artificial surfaces → urban, 7–8 mines
//!   and dumps → sand, 10–11 green urban and sport areas → grass, 12–21 arable land, permanent
//!   crops and heterogeneous agriculture → crops, 18 pastures → grass, 22–25 agro-forestry
//!   and forests → forest, 26–28 grassland, heath, sclerophyllous → grass, 29 transitional
//!   woodland-shrub → forest, 30 beaches and dunes → sand, 31 bare rock → rock, 32–33 sparse
//!   vegetation, burnt areas → sand, 34 glaciers → snow, 35–37 marshes and bogs → grass,
//!   38–39 salines, intertidal flats → sand, 40–44 water courses, bodies, lagoons, estuaries,
//!   sea → water; 48 (no data) → none.
//!
//! A code in neither (unknown) is drawn with the derived classes and counted in the summary.
//!
//! The same table may stand in a run config (`aerie run --config ig.toml`), where it may also
//! name the raster, relative to the config's folder (`raster = "worldcover.tif"`, as
//! `--landcover`); flags given on the command line win over it.

use std::collections::BTreeMap;
use std::path::PathBuf;

use serde::{Deserialize, Serialize};

/// aerie's land-cover classes, in the shaders' order (`shaders/landcover.glsl`).
pub const CLASS_NAMES: [&str; 8] = [
    "water", "sand", "grass", "crops", "forest", "rock", "snow", "urban",
];
/// The table's value for "no class here" (the derived classes apply).
pub const NO_CLASS: u8 = 255;

/// A built-in code table.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Preset {
    WorldCover,
    Corine,
}

impl Preset {
    /// Its name in a config.
    pub fn name(self) -> &'static str {
        match self {
            Self::WorldCover => "worldcover",
            Self::Corine => "corine",
        }
    }

    pub fn parse(s: &str) -> Option<Self> {
        match s {
            "worldcover" => Some(Self::WorldCover),
            "corine" => Some(Self::Corine),
            _ => None,
        }
    }

    /// (code, class index) pairs.
    pub fn codes(self) -> Vec<(u8, u8)> {
        let [water, sand, grass, crops, forest, rock, snow, urban] = [0u8, 1, 2, 3, 4, 5, 6, 7];
        match self {
            Self::WorldCover => vec![
                (10, forest),
                (20, grass),
                (30, grass),
                (40, crops),
                (50, urban),
                (60, sand),
                (70, snow),
                (80, water),
                (90, grass),
                (95, forest),
                (100, grass),
            ],
            Self::Corine => {
                let class = |g: u8| match g {
                    1..=6 | 9 => urban,
                    7 | 8 => sand,
                    10 | 11 | 18 => grass,
                    12..=21 => crops,
                    22..=25 | 29 => forest,
                    26..=28 => grass,
                    30 | 32 | 33 | 38 | 39 => sand,
                    31 => rock,
                    34 => snow,
                    35..=37 => grass,
                    _ => water, // 40..=44
                };
                (1..=44).map(|g| (g, class(g))).collect()
            }
        }
    }
}

/// A validated `[landcover]` table.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct LandcoverMap {
    pub preset: Option<Preset>,
    /// Code → class index, or [`NO_CLASS`] for "none".
    pub codes: BTreeMap<u8, u8>,
}

impl LandcoverMap {
    /// The preset alone.
    pub fn preset(p: Preset) -> Self {
        Self {
            preset: Some(p),
            codes: BTreeMap::new(),
        }
    }

    /// Code → class index for every byte ([`NO_CLASS`] where unmapped).
    pub fn table(&self) -> [u8; 256] {
        let mut t = [NO_CLASS; 256];
        for (code, class) in self.preset.map(Preset::codes).unwrap_or_default() {
            t[code as usize] = class;
        }
        for (&code, &class) in &self.codes {
            t[code as usize] = class;
        }
        t
    }
}

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawFile {
    landcover: Option<RawLandcover>,
}

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawLandcover {
    raster: Option<PathBuf>,
    preset: Option<String>,
    #[serde(default)]
    codes: BTreeMap<String, String>,
}

/// A run config's `[landcover]` table: the code mapping and, optionally, the raster.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct LandcoverSettings {
    /// The land-cover raster, relative to the config's folder (`--landcover` wins over it).
    pub raster: Option<PathBuf>,
    pub map: LandcoverMap,
}

impl Serialize for LandcoverSettings {
    /// Written back as the table it was read from (a config's `to_toml` round trip).
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        use serde::ser::SerializeMap;
        let mut m = s.serialize_map(None)?;
        if let Some(r) = &self.raster {
            m.serialize_entry("raster", r)?;
        }
        if let Some(p) = self.map.preset {
            m.serialize_entry("preset", p.name())?;
        }
        if !self.map.codes.is_empty() {
            let codes: BTreeMap<String, &str> = self
                .map
                .codes
                .iter()
                .map(|(&code, &class)| (code.to_string(), class_name(class)))
                .collect();
            m.serialize_entry("codes", &codes)?;
        }
        m.end()
    }
}

fn class_name(class: u8) -> &'static str {
    CLASS_NAMES.get(class as usize).copied().unwrap_or("none")
}

impl RawLandcover {
    /// Validates the table; errors are (dotted key, reason).
    pub(crate) fn validate(self) -> Result<LandcoverSettings, (String, String)> {
        let preset = match self.preset.as_deref() {
            None => None,
            Some(p) => Some(Preset::parse(p).ok_or_else(|| {
                (
                    "landcover.preset".to_owned(),
                    format!("`{p}` is not a preset (worldcover, corine)"),
                )
            })?),
        };
        let mut codes = BTreeMap::new();
        for (k, v) in &self.codes {
            let key = format!("landcover.codes.{k}");
            let code: u8 = k
                .parse()
                .ok()
                .filter(|&c| c != NO_CLASS)
                .ok_or_else(|| (key.clone(), "the key must be a raster code 0..=254".into()))?;
            let class = if v == "none" {
                NO_CLASS
            } else {
                CLASS_NAMES.iter().position(|n| n == v).ok_or_else(|| {
                    (
                        key.clone(),
                        format!("`{v}` is not a class ({}, none)", CLASS_NAMES.join(", ")),
                    )
                })? as u8
            };
            codes.insert(code, class);
        }
        if preset.is_none() && codes.is_empty() {
            return Err((
                "landcover".to_owned(),
                "[landcover] needs a preset or [landcover.codes]".to_owned(),
            ));
        }
        if self
            .raster
            .as_ref()
            .is_some_and(|r| r.as_os_str().is_empty())
        {
            return Err((
                "landcover.raster".to_owned(),
                "must name a GeoTIFF of class codes".to_owned(),
            ));
        }
        Ok(LandcoverSettings {
            raster: self.raster,
            map: LandcoverMap { preset, codes },
        })
    }
}

/// Parses a TOML text holding a `[landcover]` table (a `--landcover-map` file); errors name
/// `source` and the key. The raster is named by `--landcover` there, not in the table.
pub fn parse_landcover(text: &str, source: &str) -> Result<LandcoverMap, String> {
    let raw: RawFile =
        toml::from_str(text).map_err(|e| format!("{source}: {}", e.message().trim()))?;
    let raw = raw
        .landcover
        .ok_or_else(|| format!("{source}: no [landcover] table"))?;
    if raw.raster.is_some() {
        return Err(format!(
            "{source}: landcover.raster: a --landcover-map file maps codes only; name the raster with --landcover (or put the table in the run config)"
        ));
    }
    let s = raw
        .validate()
        .map_err(|(key, why)| format!("{source}: {key}: {why}"))?;
    Ok(s.map)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn presets_map_their_documented_codes() {
        let t = LandcoverMap::preset(Preset::WorldCover).table();
        assert_eq!((t[10], t[40], t[50], t[70], t[80]), (4, 3, 7, 6, 0));
        assert_eq!((t[0], t[15], t[255]), (NO_CLASS, NO_CLASS, NO_CLASS));
        let c = LandcoverMap::preset(Preset::Corine).table();
        assert_eq!(
            (c[1], c[12], c[18], c[24], c[31], c[34], c[44]),
            (7, 3, 2, 4, 5, 6, 0)
        );
        assert_eq!((c[0], c[48]), (NO_CLASS, NO_CLASS));
    }

    #[test]
    fn codes_override_the_preset_and_errors_name_the_key() {
        let m = parse_landcover(
            "[landcover]\npreset = \"worldcover\"\n[landcover.codes]\n10 = \"rock\"\n200 = \"urban\"\n30 = \"none\"\n",
            "lc.toml",
        )
        .unwrap();
        let t = m.table();
        assert_eq!((t[10], t[200], t[30], t[40]), (5, 7, NO_CLASS, 3));
        for (text, want) in [
            ("[landcover]\npreset = \"modis\"\n", "landcover.preset"),
            (
                "[landcover.codes]\n300 = \"forest\"\n",
                "landcover.codes.300",
            ),
            ("[landcover.codes]\n12 = \"jungle\"\n", "landcover.codes.12"),
            ("[landcover]\n", "needs a preset"),
            (
                "[landcover]\npreset = \"corine\"\nraster = \"a.tif\"\n",
                "--landcover",
            ),
            ("[other]\n", "lc.toml"),
        ] {
            let e = parse_landcover(text, "lc.toml").unwrap_err();
            assert!(e.starts_with("lc.toml") && e.contains(want), "{text}: {e}");
        }
    }
}
