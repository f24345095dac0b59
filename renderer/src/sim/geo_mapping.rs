//! Where a host's geodetic positions land in the dataset's world frame and on its grid
//! (`GeoMapping`), for the poses, the entities and the terrain queries.

use glam::DVec3;

use aerie_terrain::camera::Attitude;
use aerie_terrain::dataset::Dataset;
use aerie_terrain::geodesy::{GeoGrid, Geodetic};
use aerie_terrain::GeoReference;

/// Where geodetic positions land for a geographic dataset.
///
/// **World** ([`GeoMapping::to_world`], poses and the camera): a geographic grid (SRTM `.hgt`,
/// geographic GeoTIFF, stitched tiles) is drawn on the WGS84 ellipsoid, in the East-North-Up
/// frame tangent at its south-west sample (height 0) — `aerie_terrain::geodesy::GeoGrid`. A
/// geodetic pose is placed at exactly its point in that frame, its attitude taken in the
/// north-east-down frame at the aircraft's own position ([`GeoMapping::attitude_at`]), so
/// headings are from true north there and a level attitude is level over that ground however
/// far the aircraft is from the origin. Altitudes are in the data's vertical datum (metres
/// above mean sea level for SRTM, as CIGI sends them); the geoid is not applied — it would
/// move terrain and aircraft alike (PROTOCOL.md "Datums").
///
/// **Grid metres** ([`GeoMapping::to_local`], the terrain queries' lookups): sample (col, row)
/// at `x = col · spacing_x`, `y = row · spacing_y`, the index the heights are stored by:
///
/// ```text
/// x = (lon − west_lon) / dlon · spacing_x      y = (lat − south_lat) / dlat · spacing_y
/// ```
///
/// Longitudes are taken the short way round from `west_lon`. On a UTM grid
/// ([`GeoMapping::projected`]) grid metres are easting/northing from sample (0, 0) instead, through
/// the zone's transverse Mercator projection, and the fields above are that sample's latitude
/// and longitude with steps 0.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GeoMapping {
    pub south_lat_deg: f64,
    pub west_lon_deg: f64,
    pub dlat_deg: f64,
    pub dlon_deg: f64,
    pub spacing_x: f64,
    pub spacing_y: f64,
    /// A UTM grid: its placement on the ellipsoid (`None` for a geographic grid).
    pub projected: Option<GeoGrid>,
}

impl GeoMapping {
    /// The mapping of a dataset with a geographic geo-reference; `Err` names why there is none.
    pub fn of_dataset(ds: &Dataset) -> Result<Self, String> {
        Self::of_grid(&ds.hf.geo, [ds.hf.spacing_x, ds.hf.spacing_y], &ds.source)
    }

    /// As [`Self::of_dataset`] for a grid without its samples (a streamed store's).
    pub fn of_source(grid: &aerie_terrain::source::SourceGrid) -> Result<Self, String> {
        Self::of_grid(
            &grid.geo,
            [grid.spacing_x, grid.spacing_y],
            &grid.description,
        )
    }

    /// The mapping of a grid with geo-reference `geo` and index spacings (metres); `name` is
    /// the dataset's, for the refusal.
    pub fn of_grid(
        geo: &Option<GeoReference>,
        [spacing_x, spacing_y]: [f64; 2],
        name: &str,
    ) -> Result<Self, String> {
        match geo {
            Some(GeoReference::Geographic {
                south_lat_deg,
                west_lon_deg,
                dlat_deg,
                dlon_deg,
            }) => Ok(Self {
                south_lat_deg: *south_lat_deg,
                west_lon_deg: *west_lon_deg,
                dlat_deg: *dlat_deg,
                dlon_deg: *dlon_deg,
                spacing_x,
                spacing_y,
                projected: None,
            }),
            Some(GeoReference::Projected { crs, .. }) => {
                match GeoGrid::of(geo.as_ref(), spacing_x, spacing_y) {
                    Some(g) => Ok(Self {
                        south_lat_deg: g.south_lat_deg,
                        west_lon_deg: g.west_lon_deg,
                        dlat_deg: 0.0,
                        dlon_deg: 0.0,
                        spacing_x,
                        spacing_y,
                        projected: Some(g),
                    }),
                    None => Err(format!(
                        "{name}: projected grid ({crs}) not in a UTM zone on WGS84; geodetic poses need a geographic or UTM dataset, send local x/y/z instead"
                    )),
                }
            }
            None => Err(format!(
                "{name}: no geo-reference; geodetic poses need a geo-referenced dataset (e.g. SRTM .hgt), send local x/y/z instead"
            )),
        }
    }

    /// The grid on the ellipsoid these fields describe.
    pub fn grid(&self) -> GeoGrid {
        if let Some(g) = self.projected {
            return g;
        }
        let geo = GeoReference::Geographic {
            south_lat_deg: self.south_lat_deg,
            west_lon_deg: self.west_lon_deg,
            dlat_deg: self.dlat_deg,
            dlon_deg: self.dlon_deg,
        };
        // `of_dataset` only builds mappings of valid geographic grids; a hand-made invalid one
        // falls back to positive steps so that nothing divides by zero.
        GeoGrid::of(Some(&geo), self.spacing_x, self.spacing_y).unwrap_or_else(|| {
            let fixed = GeoReference::Geographic {
                south_lat_deg: self.south_lat_deg,
                west_lon_deg: self.west_lon_deg,
                dlat_deg: 1.0 / 1200.0,
                dlon_deg: 1.0 / 1200.0,
            };
            GeoGrid::of(Some(&fixed), 1.0, 1.0).expect("valid fallback grid")
        })
    }

    /// Latitude/longitude (degrees) and altitude (metres, the data's datum) → world metres:
    /// the exact point on the ellipsoid in the dataset's world frame.
    pub fn to_world(&self, lat_deg: f64, lon_deg: f64, alt_m: f64) -> DVec3 {
        self.grid()
            .world_of_geodetic(Geodetic::new(lat_deg, lon_deg, alt_m))
    }

    /// World metres → (latitude, longitude in [−180, 180), altitude).
    pub fn world_to_geodetic(&self, p: DVec3) -> (f64, f64, f64) {
        let g = self.grid().geodetic_of_world(p);
        (
            g.lat_deg,
            (g.lon_deg + 180.0).rem_euclid(360.0) - 180.0,
            g.alt_m,
        )
    }

    /// An attitude sent for an aircraft at (lat, lon) — heading from true north there, pitch
    /// and roll against that point's horizon — in the world frame.
    pub fn attitude_at(&self, lat_deg: f64, lon_deg: f64, attitude: Attitude) -> Attitude {
        attitude.in_frame(self.grid().local_enu_axes(lat_deg, lon_deg))
    }

    /// Latitude/longitude (degrees) and altitude (metres) → grid metres (z: the altitude).
    pub fn to_local(&self, lat_deg: f64, lon_deg: f64, alt_m: f64) -> DVec3 {
        if let Some(g) = &self.projected {
            return g.grid_of_lat_lon(lat_deg, lon_deg).extend(alt_m);
        }
        let dlon = (lon_deg - self.west_lon_deg + 180.0).rem_euclid(360.0) - 180.0;
        DVec3::new(
            dlon / self.dlon_deg * self.spacing_x,
            (lat_deg - self.south_lat_deg) / self.dlat_deg * self.spacing_y,
            alt_m,
        )
    }

    /// Grid metres → (latitude, longitude in [−180, 180), altitude).
    pub fn to_geodetic(&self, p: DVec3) -> (f64, f64, f64) {
        if let Some(g) = &self.projected {
            let (lat, lon) = g.lat_lon_of_grid(p.truncate());
            return (lat, (lon + 180.0).rem_euclid(360.0) - 180.0, p.z);
        }
        let lon = self.west_lon_deg + p.x / self.spacing_x * self.dlon_deg;
        (
            self.south_lat_deg + p.y / self.spacing_y * self.dlat_deg,
            (lon + 180.0).rem_euclid(360.0) - 180.0,
            p.z,
        )
    }
}
