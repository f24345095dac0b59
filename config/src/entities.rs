//! The `[entities]` table: how a CIGI host's other entities are drawn — which model each
//! entity type uses, and the discrete level-of-detail selection (document 004: three levels
//! chosen by the bounding sphere's projected size, with hysteresis against popping).
//!
//! ```toml
//! [entities]
//! lod_thresholds_px = [48.0, 12.0]  # projected bounding radius (px) at and above which level 0,
//!                                   # resp. level 1, is drawn; below the last, level 2
//! hysteresis = 0.10                 # band around each threshold, fraction in [0, 1)
//! scale = 1.0                       # factor applied to every model, (0, 1000]
//!
//! [entities.types]                  # CIGI entity type (0..=65535) → glTF 2.0 model
//! 1234 = "models/c172.glb"          # relative paths are relative to the config file's folder
//! ```
//!
//! A type not in the table is drawn with the built-in default model. Validation follows
//! document 004: thresholds ordered (level 0's above level 1's), hysteresis below 100 %, and —
//! so that the bands of two thresholds never overlap — `t1·(1+h) < t0·(1−h)`.

use std::collections::BTreeMap;
use std::path::PathBuf;

use serde::{Deserialize, Serialize};

/// Levels of detail of every model (document 004's near, middle and far).
pub const LOD_LEVELS: usize = 3;
/// Default thresholds: level 0 from 48 px of projected radius, level 1 from 12 px.
pub const DEFAULT_LOD_THRESHOLDS_PX: [f64; LOD_LEVELS - 1] = [48.0, 12.0];
/// Document 004's default hysteresis, 10 %.
pub const DEFAULT_HYSTERESIS: f64 = 0.10;

/// The validated `[entities]` table.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct EntitySettings {
    /// Projected bounding-sphere radius in pixels at and above which level `l` is drawn
    /// (strictly decreasing, finite, > 0).
    pub lod_thresholds_px: [f64; LOD_LEVELS - 1],
    /// Hysteresis band around each threshold, as a fraction of it, in [0, 1).
    pub hysteresis: f64,
    /// Factor applied to every model's size.
    pub scale: f64,
    /// Entity type → model path (as written, not resolved).
    #[serde(
        skip_serializing_if = "BTreeMap::is_empty",
        serialize_with = "types_as_strings"
    )]
    pub types: BTreeMap<u16, PathBuf>,
}

impl Default for EntitySettings {
    fn default() -> Self {
        Self {
            lod_thresholds_px: DEFAULT_LOD_THRESHOLDS_PX,
            hysteresis: DEFAULT_HYSTERESIS,
            scale: 1.0,
            types: BTreeMap::new(),
        }
    }
}

impl EntitySettings {
    /// True when every value is the default (nothing to write back).
    pub fn is_default(&self) -> bool {
        *self == Self::default()
    }
}

/// TOML table keys are strings.
fn types_as_strings<S: serde::Serializer>(
    types: &BTreeMap<u16, PathBuf>,
    s: S,
) -> Result<S::Ok, S::Error> {
    s.collect_map(types.iter().map(|(k, v)| (k.to_string(), v)))
}

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields, expecting = "a table of entity settings")]
pub(crate) struct RawEntities {
    lod_thresholds_px: Option<Vec<f64>>,
    hysteresis: Option<f64>,
    scale: Option<f64>,
    #[serde(default)]
    types: BTreeMap<String, PathBuf>,
}

/// Checks the thresholds and the hysteresis together (document 004's rules). The error is
/// (dotted key, reason).
pub fn check_lod(thresholds: &[f64], hysteresis: f64) -> Result<(), (String, String)> {
    let tkey = "entities.lod_thresholds_px".to_owned();
    if thresholds.len() != LOD_LEVELS - 1 {
        return Err((
            tkey,
            format!(
                "must list {} thresholds (one between each pair of the {LOD_LEVELS} levels), got {}",
                LOD_LEVELS - 1,
                thresholds.len()
            ),
        ));
    }
    if let Some(t) = thresholds.iter().find(|t| !(t.is_finite() && **t > 0.0)) {
        return Err((
            tkey,
            format!("every threshold must be a finite number of pixels > 0, got {t}"),
        ));
    }
    if thresholds.windows(2).any(|w| w[0] <= w[1]) {
        return Err((
            tkey,
            format!(
                "must be strictly decreasing (level 0, the finest, needs the largest projected size), got {thresholds:?}"
            ),
        ));
    }
    let hkey = "entities.hysteresis".to_owned();
    if !(hysteresis.is_finite() && (0.0..1.0).contains(&hysteresis)) {
        return Err((
            hkey,
            format!("must be a fraction at least 0 and below 1 (100 %), got {hysteresis}"),
        ));
    }
    for w in thresholds.windows(2) {
        if w[1] * (1.0 + hysteresis) >= w[0] * (1.0 - hysteresis) {
            return Err((
                hkey,
                format!(
                    "the bands of thresholds {} px and {} px overlap at hysteresis {hysteresis} ({} ≥ {}): lower it or move the thresholds apart",
                    w[0],
                    w[1],
                    w[1] * (1.0 + hysteresis),
                    w[0] * (1.0 - hysteresis)
                ),
            ));
        }
    }
    Ok(())
}

impl RawEntities {
    pub(crate) fn validate(self) -> Result<EntitySettings, (String, String)> {
        let d = EntitySettings::default();
        let thresholds = self
            .lod_thresholds_px
            .unwrap_or_else(|| d.lod_thresholds_px.to_vec());
        let hysteresis = self.hysteresis.unwrap_or(d.hysteresis);
        check_lod(&thresholds, hysteresis)?;
        let scale = self.scale.unwrap_or(d.scale);
        if !(scale.is_finite() && scale > 0.0 && scale <= 1000.0) {
            return Err((
                "entities.scale".to_owned(),
                format!("must be greater than 0 and at most 1000, got {scale}"),
            ));
        }
        let mut types = BTreeMap::new();
        for (key, path) in self.types {
            let dotted = crate::path_de::dotted(&[
                crate::path_de::Segment::Key("entities".into()),
                crate::path_de::Segment::Key("types".into()),
                crate::path_de::Segment::Key(key.clone()),
            ]);
            let n = match key.parse::<u16>() {
                Ok(n) if n.to_string() == key => n,
                _ => {
                    return Err((
                        dotted,
                        format!(
                            "an entity type must be an integer 0..=65535 written without sign or leading zeros (CIGI Entity Control's entity type), got `{key}`"
                        ),
                    ))
                }
            };
            if path.as_os_str().is_empty() {
                return Err((dotted, "must not be empty".to_owned()));
            }
            let ext = path
                .extension()
                .and_then(|e| e.to_str())
                .map(str::to_ascii_lowercase);
            if !matches!(ext.as_deref(), Some("gltf" | "glb")) {
                return Err((
                    dotted,
                    format!(
                        "must be a glTF 2.0 model (.gltf or .glb), got {}",
                        path.display()
                    ),
                ));
            }
            types.insert(n, path);
        }
        Ok(EntitySettings {
            lod_thresholds_px: [thresholds[0], thresholds[1]],
            hysteresis,
            scale,
            types,
        })
    }
}

#[cfg(test)]
mod tests {
    use crate::parse;

    #[test]
    fn defaults_and_a_full_table() {
        let c = parse("", "t.toml").unwrap();
        assert_eq!(c.entities, super::EntitySettings::default());
        assert_eq!(c.entities.hysteresis, 0.10);
        let text = "[entities]\nlod_thresholds_px = [100.0, 20.0]\nhysteresis = 0.2\nscale = 2.0\n[entities.types]\n1234 = \"models/c172.glb\"\n7 = \"truck.gltf\"\n";
        let c = parse(text, "t.toml").unwrap();
        assert_eq!(c.entities.lod_thresholds_px, [100.0, 20.0]);
        assert_eq!(c.entities.hysteresis, 0.2);
        assert_eq!(c.entities.scale, 2.0);
        assert_eq!(
            c.entities.types.get(&1234).unwrap().to_str(),
            Some("models/c172.glb")
        );
        assert_eq!(c.entities.types.len(), 2);
        let again = parse(&c.to_toml().unwrap(), "again.toml").unwrap();
        assert_eq!(again.entities, c.entities);
    }

    #[test]
    fn bad_values_are_refused_naming_the_key() {
        for (text, key, why) in [
            (
                "lod_thresholds_px = [10.0, 20.0]",
                "entities.lod_thresholds_px",
                "decreasing",
            ),
            (
                "lod_thresholds_px = [10.0, 10.0]",
                "entities.lod_thresholds_px",
                "decreasing",
            ),
            (
                "lod_thresholds_px = [10.0]",
                "entities.lod_thresholds_px",
                "2 thresholds",
            ),
            (
                "lod_thresholds_px = [10.0, -1.0]",
                "entities.lod_thresholds_px",
                "> 0",
            ),
            ("hysteresis = 1.0", "entities.hysteresis", "below 1"),
            ("hysteresis = 1.5", "entities.hysteresis", "below 1"),
            ("hysteresis = -0.1", "entities.hysteresis", "below 1"),
            ("hysteresis = nan", "entities.hysteresis", "below 1"),
            // 20·1.4 = 28 ≥ 30·0.6 = 18: the two bands overlap.
            (
                "lod_thresholds_px = [30.0, 20.0]\nhysteresis = 0.4",
                "entities.hysteresis",
                "overlap",
            ),
            ("scale = 0.0", "entities.scale", "greater than 0"),
            (
                "[entities.types]\n70000 = \"a.glb\"",
                "entities.types.70000",
                "0..=65535",
            ),
            (
                "[entities.types]\n01 = \"a.glb\"",
                "entities.types.01",
                "leading zeros",
            ),
            (
                "[entities.types]\n5 = \"a.obj\"",
                "entities.types.5",
                "glTF",
            ),
            ("[entities.types]\n5 = \"\"", "entities.types.5", "empty"),
        ] {
            let e = parse(&format!("[entities]\n{text}\n"), "t.toml")
                .unwrap_err()
                .to_string();
            assert!(e.contains(key), "{text:?}: {e}");
            assert!(e.contains(why), "{text:?}: {e}");
            assert!(e.starts_with("t.toml:"), "{e}");
        }
        // Unknown keys are refused too.
        let e = parse("[entities]\nlod = 3\n", "t.toml")
            .unwrap_err()
            .to_string();
        assert!(e.contains("lod"), "{e}");
    }
}
