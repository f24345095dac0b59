//! The `[databases]` table: which dataset a CIGI host's Database Number selects.
//!
//! ```toml
//! [databases]
//! 1 = "dem/N47E011.hgt.zip"   # relative paths are relative to the config file's folder
//! 2 = "dem/sierra/"           # a folder of tiles, stitched, as `--dem` takes it
//! ```
//!
//! Keys are CIGI database numbers 1..=127: IG Control carries a signed byte where 0 means "no
//! change" and the IG reports −n in Start of Frame while database n loads, so neither 0 nor a
//! negative number can name a dataset.

use std::collections::BTreeMap;
use std::path::PathBuf;

use serde::Serialize;

/// Highest CIGI database number (IG Control's signed byte).
pub const MAX_DATABASE: i8 = 127;

/// Database number → dataset path (as written in the file, not resolved).
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
#[serde(transparent)]
pub struct Databases(pub BTreeMap<String, PathBuf>);

impl Databases {
    /// True when no database is configured.
    pub fn is_empty(&self) -> bool {
        self.0.is_empty()
    }

    /// The dataset of database `n`, if configured.
    pub fn path(&self, n: i8) -> Option<&PathBuf> {
        self.0.get(&n.to_string())
    }

    /// Every (number, path), by ascending number.
    pub fn iter(&self) -> impl Iterator<Item = (i8, &PathBuf)> {
        let mut v: Vec<(i8, &PathBuf)> = self
            .0
            .iter()
            .filter_map(|(k, p)| k.parse::<i8>().ok().map(|n| (n, p)))
            .collect();
        v.sort_by_key(|(n, _)| *n);
        v.into_iter()
    }
}

/// Checks every key and path; the error is (dotted key, reason).
pub(crate) fn validate(raw: BTreeMap<String, PathBuf>) -> Result<Databases, (String, String)> {
    for (key, path) in &raw {
        let dotted = crate::path_de::dotted(&[
            crate::path_de::Segment::Key("databases".into()),
            crate::path_de::Segment::Key(key.clone()),
        ]);
        match key.parse::<i64>() {
            Ok(n) if (1..=i64::from(MAX_DATABASE)).contains(&n) && n.to_string() == *key => {}
            _ => {
                return Err((
                    dotted,
                    format!(
                        "a database number must be an integer 1..={MAX_DATABASE} written without sign or leading zeros (CIGI: 0 means no change, negative numbers mean loading), got `{key}`"
                    ),
                ))
            }
        }
        if path.as_os_str().is_empty() {
            return Err((dotted, "must not be empty".to_owned()));
        }
    }
    Ok(Databases(raw))
}

#[cfg(test)]
mod tests {
    use crate::parse;

    #[test]
    fn numbers_name_datasets() {
        let c = parse("[databases]\n1 = \"a.hgt\"\n127 = \"tiles/\"\n", "t.toml").unwrap();
        assert_eq!(c.databases.path(1).unwrap().to_str(), Some("a.hgt"));
        assert_eq!(c.databases.path(127).unwrap().to_str(), Some("tiles/"));
        assert_eq!(c.databases.path(2), None);
        let all: Vec<i8> = c.databases.iter().map(|(n, _)| n).collect();
        assert_eq!(all, vec![1, 127]);
        // Written back and read again: the same table.
        let again = parse(&c.to_toml().unwrap(), "again.toml").unwrap();
        assert_eq!(again.databases, c.databases);
    }

    #[test]
    fn bad_numbers_and_paths_name_their_key() {
        for (text, key) in [
            ("[databases]\n0 = \"a.hgt\"\n", "databases.0"),
            ("[databases]\n128 = \"a.hgt\"\n", "databases.128"),
            ("[databases]\n-3 = \"a.hgt\"\n", "databases.-3"),
            ("[databases]\n01 = \"a.hgt\"\n", "databases.01"),
            ("[databases]\nalps = \"a.hgt\"\n", "databases.alps"),
            ("[databases]\n5 = \"\"\n", "databases.5"),
        ] {
            let e = parse(text, "t.toml").unwrap_err().to_string();
            assert!(e.contains(key), "{text:?}: {e}");
            assert!(e.starts_with("t.toml:"), "{e}");
        }
        let e = parse("[databases]\n1 = 5\n", "t.toml")
            .unwrap_err()
            .to_string();
        assert!(e.contains("databases.1"), "{e}");
    }
}
