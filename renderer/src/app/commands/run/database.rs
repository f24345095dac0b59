//! CIGI Database Number → the dataset drawn (issue 12 item 3): the `[databases]` table names a
//! dataset per number; a host's request starts loading it on a worker thread while frames go on
//! with the current terrain, Start of Frame saying −n until it is ready, then n.
//!
//! [`DatabaseChoice`] is the decision (pure, tested); [`DatabaseLoader`] runs one load.

use std::path::{Path, PathBuf};
use std::sync::mpsc;

use aerie_config::Databases;
use aerie_terrain::query::InMemorySource;

use crate::app::args::StoreArgs;
use crate::app::prepare::{prepare_source, Terrain};
use crate::render::desc::RendererDesc;

/// What Start of Frame reports about the database.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DatabaseReport {
    /// Database n is drawn (0: the `--dem` dataset, not in the table).
    Ready(i8),
    /// Database n is loading (Start of Frame sends −n).
    Loading(i8),
    /// The host's last request names a number the table does not have (CIGI: −128); the
    /// current terrain stays drawn.
    Unavailable,
}

/// What to do about a host's database request this frame.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum DatabaseAction {
    /// Nothing new.
    None,
    /// Start loading database n from this path.
    Load(i8, PathBuf),
    /// The host asked for a number the table does not have (told once per number).
    Unknown(i8),
}

/// The database state of one run: which number is drawn, which one is loading, which requests
/// were refused.
#[derive(Clone, Debug)]
pub struct DatabaseChoice {
    table: Databases,
    base: PathBuf,
    current: i8,
    loading: Option<i8>,
    /// The last request acted on (a host repeats its number in every IG Control).
    last_request: i8,
    /// The last request was for a number the table does not have.
    unavailable: bool,
}

impl DatabaseChoice {
    /// `table` as configured (paths relative to `config_dir`), drawing `dem` at start: its
    /// number is the table entry with the same path, else 0.
    pub fn new(table: Databases, config_dir: &Path, dem: &Path) -> Self {
        let base = config_dir.to_path_buf();
        let current = table
            .iter()
            .find(|(_, p)| same_path(&base.join(p), dem))
            .map_or(0, |(n, _)| n);
        Self {
            table,
            base,
            current,
            loading: None,
            last_request: 0,
            unavailable: false,
        }
    }

    /// The report for this frame's Start of Frame.
    pub fn report(&self) -> DatabaseReport {
        match self.loading {
            Some(n) => DatabaseReport::Loading(n),
            None if self.unavailable => DatabaseReport::Unavailable,
            None => DatabaseReport::Ready(self.current),
        }
    }

    /// The host's Database Number of its latest IG Control (0 = no change; negative values are
    /// the IG's own "loading" convention and mean nothing from a host).
    pub fn request(&mut self, requested: i8) -> DatabaseAction {
        if requested <= 0 || requested == self.last_request {
            return DatabaseAction::None;
        }
        self.last_request = requested;
        self.unavailable = false;
        if requested == self.current && self.loading.is_none() {
            return DatabaseAction::None;
        }
        if self.loading.is_some() {
            // One load at a time: the newest request is acted on when this one finishes.
            self.last_request = 0;
            return DatabaseAction::None;
        }
        match self.table.path(requested) {
            Some(p) => {
                self.loading = Some(requested);
                DatabaseAction::Load(requested, self.base.join(p))
            }
            None => {
                self.unavailable = true;
                DatabaseAction::Unknown(requested)
            }
        }
    }

    /// The load of database n finished: drawn now when `ok`; else the old one stays drawn and
    /// Start of Frame says the request is unavailable until the host asks for another.
    pub fn finished(&mut self, n: i8, ok: bool) {
        if self.loading == Some(n) {
            self.loading = None;
            if ok {
                self.current = n;
            } else {
                self.unavailable = true;
            }
        }
    }

    /// Database numbers configured, for the summary.
    pub fn configured(&self) -> Vec<i8> {
        self.table.iter().map(|(n, _)| n).collect()
    }
}

fn same_path(a: &Path, b: &Path) -> bool {
    match (a.canonicalize(), b.canonicalize()) {
        (Ok(x), Ok(y)) => x == y,
        _ => a == b,
    }
}

/// A loaded database: the terrain (a dataset in memory, or a tile store streamed exactly as
/// `--dem region.aerie` is) and, for a dataset in memory, the query service on it (built on
/// the loader thread too: on a 16385² grid its hierarchy takes seconds; `Err` says why there is
/// none). A streamed store's queries read its resident pages and need no building.
pub struct LoadedTerrain {
    pub terrain: Terrain,
    pub queries: Option<Result<InMemorySource, String>>,
}

/// One dataset loading on a worker thread.
pub struct DatabaseLoader {
    pub number: i8,
    pub path: PathBuf,
    rx: mpsc::Receiver<Result<LoadedTerrain, String>>,
}

impl DatabaseLoader {
    /// Starts loading `path` for a renderer made with `desc` (the same preparation as
    /// `--dem`: a store is streamed within `store`'s cache, its coarsest level waited for on
    /// this thread; any other file is loaded whole with its bake).
    pub fn start(number: i8, path: PathBuf, desc: &RendererDesc, store: &StoreArgs) -> Self {
        let (tx, rx) = mpsc::channel();
        let p = path.clone();
        let (desc, store) = (desc.clone(), store.clone());
        std::thread::Builder::new()
            .name(format!("aerie-database-{number}"))
            .spawn(move || {
                let r = prepare_source(&p, &desc, &store)
                    .map(|terrain| LoadedTerrain {
                        queries: terrain.dataset.as_ref().map(|ds| {
                            InMemorySource::new(ds.clone(), terrain.bake.clone())
                                .map_err(|e| e.to_string())
                        }),
                        terrain,
                    })
                    .map_err(|f| f.message);
                let _ = tx.send(r);
            })
            .map_or_else(
                |e| tracing::error!("database {number}: cannot start the loader: {e}"),
                |_| {},
            );
        Self { number, path, rx }
    }

    /// The result once the load is done (`None` while it runs).
    pub fn poll(&self) -> Option<Result<LoadedTerrain, String>> {
        match self.rx.try_recv() {
            Ok(r) => Some(r),
            Err(mpsc::TryRecvError::Empty) => None,
            Err(mpsc::TryRecvError::Disconnected) => {
                Some(Err("the loader thread stopped without a result".into()))
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::BTreeMap;

    fn table() -> Databases {
        let mut m = BTreeMap::new();
        m.insert("1".to_string(), PathBuf::from("a.hgt"));
        m.insert("2".to_string(), PathBuf::from("b.hgt"));
        Databases(m)
    }

    #[test]
    fn a_request_loads_then_reports_ready() {
        let mut c = DatabaseChoice::new(table(), Path::new("/cfg"), Path::new("/cfg/a.hgt"));
        assert_eq!(
            c.report(),
            DatabaseReport::Ready(1),
            "the --dem is database 1"
        );
        assert_eq!(c.request(0), DatabaseAction::None, "0 means no change");
        assert_eq!(c.request(1), DatabaseAction::None, "already drawn");
        assert_eq!(
            c.request(2),
            DatabaseAction::Load(2, PathBuf::from("/cfg/b.hgt"))
        );
        assert_eq!(c.report(), DatabaseReport::Loading(2));
        // The host repeats its number every frame: one load only.
        assert_eq!(c.request(2), DatabaseAction::None);
        c.finished(2, true);
        assert_eq!(c.report(), DatabaseReport::Ready(2));
        // Back to 1, and a failed load keeps 2 drawn, reported unavailable (−128) until the
        // host asks for another number.
        assert!(matches!(c.request(1), DatabaseAction::Load(1, _)));
        c.finished(1, false);
        assert_eq!(c.report(), DatabaseReport::Unavailable);
        assert_eq!(
            c.request(1),
            DatabaseAction::None,
            "not retried every frame"
        );
        assert_eq!(c.request(2), DatabaseAction::None, "2 is drawn");
        assert_eq!(c.report(), DatabaseReport::Ready(2));
    }

    #[test]
    fn unknown_and_negative_numbers_change_nothing() {
        let mut c = DatabaseChoice::new(table(), Path::new("/cfg"), Path::new("/elsewhere.hgt"));
        assert_eq!(c.report(), DatabaseReport::Ready(0));
        assert_eq!(c.request(-2), DatabaseAction::None);
        assert_eq!(c.request(9), DatabaseAction::Unknown(9));
        assert_eq!(c.request(9), DatabaseAction::None, "told once");
        assert_eq!(c.report(), DatabaseReport::Unavailable);
        // Asking for the drawn one again clears it.
        let mut c2 = DatabaseChoice::new(table(), Path::new("/cfg"), Path::new("/cfg/a.hgt"));
        assert_eq!(c2.request(9), DatabaseAction::Unknown(9));
        assert_eq!(c2.request(1), DatabaseAction::None);
        assert_eq!(c2.report(), DatabaseReport::Ready(1));
        assert_eq!(c.configured(), vec![1, 2]);
    }

    #[test]
    fn a_request_during_a_load_waits_for_it() {
        let mut c = DatabaseChoice::new(table(), Path::new("/cfg"), Path::new("/x.hgt"));
        assert!(matches!(c.request(1), DatabaseAction::Load(1, _)));
        assert_eq!(c.request(2), DatabaseAction::None);
        c.finished(1, true);
        // The host still asks for 2: acted on now.
        assert!(matches!(c.request(2), DatabaseAction::Load(2, _)));
    }
}
