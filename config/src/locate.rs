//! Where a key path (tables, arrays, arrays of tables) sits in the config text, for error
//! messages with a line and column.

use std::collections::BTreeMap;
use std::fmt;

use serde::de::{Deserializer, MapAccess, SeqAccess, Visitor};
use serde::Deserialize;

use crate::error::Location;

/// One step of a key path (a table key or an array index).
#[derive(Clone, Debug, PartialEq)]
pub(crate) enum Seg {
    Key(&'static str),
    Index(usize),
}

/// A TOML document with the span of every value.
enum Node {
    Table(BTreeMap<String, toml::Spanned<Node>>),
    Array(Vec<toml::Spanned<Node>>),
    Leaf,
}

impl<'de> Deserialize<'de> for Node {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = Node;
            fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                f.write_str("any TOML value")
            }
            fn visit_bool<E>(self, _: bool) -> Result<Node, E> {
                Ok(Node::Leaf)
            }
            fn visit_i64<E>(self, _: i64) -> Result<Node, E> {
                Ok(Node::Leaf)
            }
            fn visit_u64<E>(self, _: u64) -> Result<Node, E> {
                Ok(Node::Leaf)
            }
            fn visit_f64<E>(self, _: f64) -> Result<Node, E> {
                Ok(Node::Leaf)
            }
            fn visit_str<E>(self, _: &str) -> Result<Node, E> {
                Ok(Node::Leaf)
            }
            fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Node, A::Error> {
                let mut items = Vec::new();
                while let Some(item) = seq.next_element::<toml::Spanned<Node>>()? {
                    items.push(item);
                }
                Ok(Node::Array(items))
            }
            fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<Node, A::Error> {
                let mut entries = BTreeMap::new();
                while let Some((k, v)) = map.next_entry::<String, toml::Spanned<Node>>()? {
                    entries.insert(k, v);
                }
                Ok(Node::Table(entries))
            }
        }
        d.deserialize_any(V)
    }
}

/// Line and column of the value at `path`, or of the nearest enclosing value that exists
/// (a missing key points at its table).
pub(crate) fn locate(text: &str, path: &[Seg]) -> Option<Location> {
    let owned: Vec<SegOwned> = path
        .iter()
        .map(|s| match s {
            Seg::Key(k) => SegOwned::Key((*k).to_owned()),
            Seg::Index(i) => SegOwned::Index(*i),
        })
        .collect();
    walk(text, &owned, true)
}

/// Line and column of the value of a dotted key such as `channel[1].monitor` or
/// `render.tau_px` in config `text` (for errors found after parsing, e.g. when windows open).
pub fn key_location(text: &str, key: &str) -> Option<Location> {
    let mut path = Vec::new();
    for part in key.split('.') {
        let (name, mut rest) = part.split_once('[').map_or((part, ""), |(n, r)| (n, r));
        if !name.is_empty() {
            path.push(SegOwned::Key(name.to_owned()));
        }
        while let Some((index, after)) = rest.split_once(']') {
            path.push(SegOwned::Index(index.parse().ok()?));
            rest = after.strip_prefix('[').unwrap_or(after);
        }
    }
    walk(text, &path, false)
}

/// Follows `path` through the spanned document; with `nearest`, stops at the deepest value
/// that exists instead of failing.
fn walk(text: &str, path: &[SegOwned], nearest: bool) -> Option<Location> {
    let root: Node = toml::from_str(text).ok()?;
    let mut node = &root;
    let mut span = None;
    for seg in path {
        let next = match (seg, node) {
            (SegOwned::Key(k), Node::Table(t)) => t.get(k),
            (SegOwned::Index(i), Node::Array(a)) => a.get(*i),
            _ => None,
        };
        match next {
            Some(n) => {
                span = Some(n.span());
                node = n.get_ref();
            }
            None if nearest => break,
            None => return None,
        }
    }
    span.map(|s| Location::from_offset(text, s.start))
}

enum SegOwned {
    Key(String),
    Index(usize),
}
