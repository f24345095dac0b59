//! Questions a host asks the IG about the ground, and the IG's answers, independent of the wire
//! protocol that carried them (CIGI HAT/HOT and Line of Sight requests, the native query
//! packets).
//!
//! The host side of sim-bridge never sees terrain: whoever owns it (the renderer, with the
//! full-resolution surface of its dataset) implements [`TerrainQueries`], and the IG session
//! calls it once per request at the start of an IG frame. Points are [`PosePosition`]s: geodetic
//! (latitude, longitude, altitude above the data's vertical datum — mean sea level for SRTM and
//! CIGI) or local east-north-up metres in the dataset's frame. Entity-relative CIGI requests are
//! resolved to geodetic points by the session before they get here.
//!
//! Every answer is an [`Answer`]: ready, no terrain there (outside the data, or nothing
//! loaded), or pending (the page holding the point is not resident yet: ask again next frame;
//! the session gives up after [`MAX_PENDING_FRAMES`] frames and answers "invalid").

use crate::pose::PosePosition;

/// A request still pending after this many IG frames is answered as invalid (the bound on how
/// late an answer can be when its terrain is being streamed in).
pub const MAX_PENDING_FRAMES: u32 = 8;

/// The ground under (or above) a point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Surface {
    /// Height of terrain at the point's horizontal position, metres in the data's vertical
    /// datum (HOT). Height above terrain (HAT) is the point's altitude minus this.
    pub height_m: f64,
    /// Unit surface normal in the local east-north-up frame at the point.
    pub normal_enu: [f64; 3],
}

/// The first place a line of sight meets the terrain.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LosHit {
    /// Distance from the segment's or vector's source point, metres.
    pub range_m: f64,
    /// The intersection, in the same coordinate system as the source point was given.
    pub point: PosePosition,
    /// Unit surface normal at the intersection, local east-north-up.
    pub normal_enu: [f64; 3],
}

/// An answer that may not be available yet.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Answer<T> {
    /// The answer.
    Ready(T),
    /// No terrain there: the point is outside the loaded data, or no terrain is loaded.
    NoTerrain,
    /// The terrain there is not resident yet; ask again next frame.
    Pending,
}

impl<T> Answer<T> {
    /// The answer, if ready.
    pub fn ready(self) -> Option<T> {
        match self {
            Answer::Ready(t) => Some(t),
            _ => None,
        }
    }
}

/// A line-of-sight answer: `Ready(None)` means the line is clear (no intersection in range).
pub type LosAnswer = Answer<Option<LosHit>>;

/// The terrain's side of every query. Implemented by whoever owns the terrain.
pub trait TerrainQueries {
    /// The terrain height and normal at `at`'s horizontal position.
    fn height_of_terrain(&self, at: &PosePosition) -> Answer<Surface>;

    /// The first intersection of the segment `from → to` with the terrain.
    fn line_of_sight(&self, from: &PosePosition, to: &PosePosition) -> LosAnswer;

    /// The first intersection of the ray from `from` towards `azimuth_deg` (clockwise from
    /// true north) and `elevation_deg` (up from the local horizontal, both in the local frame
    /// at `from`), between `min_range_m` and `max_range_m` from `from`.
    fn line_of_sight_vector(
        &self,
        from: &PosePosition,
        azimuth_deg: f64,
        elevation_deg: f64,
        min_range_m: f64,
        max_range_m: f64,
    ) -> LosAnswer;
}

/// No terrain at all (`aerie listen`, or before the first dataset is loaded): every answer is
/// [`Answer::NoTerrain`].
#[derive(Clone, Copy, Debug, Default)]
pub struct NoTerrain;

impl TerrainQueries for NoTerrain {
    fn height_of_terrain(&self, _: &PosePosition) -> Answer<Surface> {
        Answer::NoTerrain
    }
    fn line_of_sight(&self, _: &PosePosition, _: &PosePosition) -> LosAnswer {
        Answer::NoTerrain
    }
    fn line_of_sight_vector(&self, _: &PosePosition, _: f64, _: f64, _: f64, _: f64) -> LosAnswer {
        Answer::NoTerrain
    }
}

/// One terrain question, as the native protocol carries it (CIGI requests carry more: their
/// session turns them into calls on [`TerrainQueries`] itself).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum TerrainRequest {
    /// Height of terrain (and so height above terrain) at a point.
    HeightOfTerrain {
        /// The point.
        at: PosePosition,
    },
    /// First intersection along a segment.
    LineOfSight {
        /// Source.
        from: PosePosition,
        /// Destination.
        to: PosePosition,
    },
    /// First intersection along a vector.
    LineOfSightVector {
        /// Source.
        from: PosePosition,
        /// Degrees clockwise from true north.
        azimuth_deg: f64,
        /// Degrees up from the local horizontal.
        elevation_deg: f64,
        /// Metres.
        min_range_m: f64,
        /// Metres.
        max_range_m: f64,
    },
}

/// The answer to a [`TerrainRequest`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum TerrainReply {
    /// Answer to [`TerrainRequest::HeightOfTerrain`].
    HeightOfTerrain(Answer<Surface>),
    /// Answer to either line-of-sight request.
    LineOfSight(LosAnswer),
}

impl TerrainRequest {
    /// Asks `terrain`.
    pub fn ask(&self, terrain: &dyn TerrainQueries) -> TerrainReply {
        match *self {
            TerrainRequest::HeightOfTerrain { at } => {
                TerrainReply::HeightOfTerrain(terrain.height_of_terrain(&at))
            }
            TerrainRequest::LineOfSight { from, to } => {
                TerrainReply::LineOfSight(terrain.line_of_sight(&from, &to))
            }
            TerrainRequest::LineOfSightVector {
                from,
                azimuth_deg,
                elevation_deg,
                min_range_m,
                max_range_m,
            } => TerrainReply::LineOfSight(terrain.line_of_sight_vector(
                &from,
                azimuth_deg,
                elevation_deg,
                min_range_m,
                max_range_m,
            )),
        }
    }

    /// True when the answer is pending.
    pub fn is_pending(reply: &TerrainReply) -> bool {
        matches!(
            reply,
            TerrainReply::HeightOfTerrain(Answer::Pending)
                | TerrainReply::LineOfSight(Answer::Pending)
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A flat plane at 100 m: enough to see that requests reach the right method.
    struct Flat;
    impl TerrainQueries for Flat {
        fn height_of_terrain(&self, _: &PosePosition) -> Answer<Surface> {
            Answer::Ready(Surface {
                height_m: 100.0,
                normal_enu: [0.0, 0.0, 1.0],
            })
        }
        fn line_of_sight(&self, _: &PosePosition, _: &PosePosition) -> LosAnswer {
            Answer::Ready(None)
        }
        fn line_of_sight_vector(
            &self,
            _: &PosePosition,
            _: f64,
            _: f64,
            _: f64,
            _: f64,
        ) -> LosAnswer {
            Answer::Pending
        }
    }

    #[test]
    fn requests_reach_their_method() {
        let p = PosePosition::LocalEnu {
            x: 1.0,
            y: 2.0,
            z: 300.0,
        };
        let hot = TerrainRequest::HeightOfTerrain { at: p }.ask(&Flat);
        assert!(
            matches!(hot, TerrainReply::HeightOfTerrain(Answer::Ready(s)) if s.height_m == 100.0)
        );
        let los = TerrainRequest::LineOfSight { from: p, to: p }.ask(&Flat);
        assert_eq!(los, TerrainReply::LineOfSight(Answer::Ready(None)));
        let v = TerrainRequest::LineOfSightVector {
            from: p,
            azimuth_deg: 0.0,
            elevation_deg: -10.0,
            min_range_m: 0.0,
            max_range_m: 1000.0,
        }
        .ask(&Flat);
        assert!(TerrainRequest::is_pending(&v));
        assert!(!TerrainRequest::is_pending(&los));
        let none = TerrainRequest::HeightOfTerrain { at: p }.ask(&NoTerrain);
        assert_eq!(none, TerrainReply::HeightOfTerrain(Answer::NoTerrain));
    }
}
