//! The answer type of every query.

/// An answer that may not be available: one for one with the host protocol's
/// ready / no terrain / pending.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Lookup<T> {
    /// The answer.
    Ready(T),
    /// No real terrain there (outside the data, over padding, or not a finite point).
    NoTerrain,
    /// Level-0 tile `tile` = [tx, ty] is needed and not resident; ask again once it is.
    Pending { tile: [u32; 2] },
}

impl<T> Lookup<T> {
    /// The answer, if ready.
    pub fn ready(self) -> Option<T> {
        match self {
            Lookup::Ready(t) => Some(t),
            _ => None,
        }
    }
}
