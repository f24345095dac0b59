//! What the answers are checked against: the demo dataset as aerie loads it with
//! `aerie_terrain::query` on it (the full-resolution level-0 triangles), the geodetic ↔ grid
//! mapping restated, the SRTM samples read independently, and ownship-relative points placed
//! with the WGS84 tangent plane.

use std::sync::{Arc, OnceLock};

use aerie::terrain::bake::{bake, BakeParams};
use aerie::terrain::dataset::load_dataset;
use aerie::terrain::query::{first_hit, height_of_terrain, InMemorySource, Lookup, Ray};
use aerie::terrain::GeoReference;
use aerie_sim_bridge::{Geodetic, LocalTangentPlane};
use glam::DVec3;

use super::Srtm;
/// The demo dataset as the IG loads it, its query source, its geodetic mapping and the SRTM
/// samples read independently.
pub struct Terrain {
    pub src: InMemorySource,
    pub south: f64,
    pub west: f64,
    pub dlat: f64,
    pub dlon: f64,
    pub sx: f64,
    pub sy: f64,
    pub srtm: Srtm,
}

pub fn terrain() -> &'static Terrain {
    static T: OnceLock<Terrain> = OnceLock::new();
    T.get_or_init(|| {
        let dem = crate::demo_dem();
        let ds = load_dataset(&dem).unwrap();
        let Some(GeoReference::Geographic {
            south_lat_deg,
            west_lon_deg,
            dlat_deg,
            dlon_deg,
        }) = ds.hf.geo.clone()
        else {
            panic!("{}: not a geographic grid", dem.display())
        };
        let (sx, sy) = (ds.hf.spacing_x, ds.hf.spacing_y);
        let b = bake(&ds, BakeParams::default(), &|_, _| {});
        let src = InMemorySource::new(Arc::new(ds), Arc::new(b)).unwrap();
        Terrain {
            src,
            south: south_lat_deg,
            west: west_lon_deg,
            dlat: dlat_deg,
            dlon: dlon_deg,
            sx,
            sy,
            srtm: Srtm::read(&dem).unwrap(),
        }
    })
}

impl Terrain {
    /// Geodetic → the dataset's local metres (what `GeoMapping::to_local` computes).
    pub fn local(&self, lat: f64, lon: f64, alt: f64) -> DVec3 {
        DVec3::new(
            (lon - self.west) / self.dlon * self.sx,
            (lat - self.south) / self.dlat * self.sy,
            alt,
        )
    }

    /// Geodetic → world metres, where the IG puts a pose (what `GeoMapping::to_world`
    /// computes): East-North-Up at the grid's south-west sample on the WGS84 ellipsoid.
    pub fn world(&self, lat: f64, lon: f64, alt: f64) -> DVec3 {
        let origin = LocalTangentPlane::new(Geodetic::new(self.south, self.west, 0.0));
        origin.geodetic_to_enu(Geodetic::new(lat, lon, alt))
    }

    /// A sent attitude (heading, pitch, roll in degrees, taken at the aircraft's own position)
    /// as the world attitude the IG draws it with, degrees.
    pub fn world_attitude(&self, lat: f64, lon: f64, hpr: [f64; 3]) -> [f64; 3] {
        let at = |la: f64, lo: f64| LocalTangentPlane::new(Geodetic::new(la, lo, 0.0)).enu_axes();
        let frame = at(self.south, self.west).transpose() * at(lat, lon);
        let a = aerie::camera::Attitude::from_degrees(hpr[0], hpr[1], hpr[2]).in_frame(frame);
        [a.heading, a.pitch, a.roll].map(f64::to_degrees)
    }

    /// Height of terrain and normal from the query service; `None` where there is no terrain.
    pub fn hot(&self, lat: f64, lon: f64) -> Option<(f64, DVec3)> {
        let p = self.local(lat, lon, 0.0);
        match height_of_terrain(&self.src, p.x, p.y) {
            Lookup::Ready(g) => Some((g.height_m, g.normal)),
            Lookup::NoTerrain => None,
            Lookup::Pending { tile } => panic!("in-memory source pending on tile {tile:?}"),
        }
    }

    /// Whether local point `p` is within 1 mm of a quad's edge or diagonal, where the surface
    /// normal is either triangle's.
    pub fn on_triangle_edge(&self, p: DVec3) -> bool {
        let (u, v) = (p.x / self.sx, p.y / self.sy);
        let (fu, fv) = (u - u.floor(), v - v.floor());
        let diagonal = (fu - fv).abs() * self.sx * self.sy / self.sx.hypot(self.sy);
        [
            fu * self.sx,
            (1.0 - fu) * self.sx,
            fv * self.sy,
            (1.0 - fv) * self.sy,
            diagonal,
        ]
        .iter()
        .any(|&d| d < 1e-3)
    }

    /// First hit along `ray` (local metres): range and point, or `None` when clear.
    pub fn los(&self, ray: &Ray) -> Option<(f64, DVec3, DVec3)> {
        match first_hit(&self.src, ray) {
            Lookup::Ready(h) => h.map(|h| (h.range_m, h.point, h.normal)),
            Lookup::NoTerrain => None,
            Lookup::Pending { tile } => panic!("in-memory source pending on tile {tile:?}"),
        }
    }
}

/// CIGI's normal azimuth (clockwise from north) and elevation (above the horizontal), degrees.
pub fn normal_az_el(n: DVec3) -> (f64, f64) {
    (
        n.x.atan2(n.y).to_degrees(),
        n.z.clamp(-1.0, 1.0).asin().to_degrees(),
    )
}

/// A point `offset` (body axes: x forward, y right, z down, metres) from an entity at
/// `lat, lon, alt` with heading, pitch and roll in degrees.
pub fn entity_relative(pose: [f64; 6], offset: [f64; 3]) -> Geodetic {
    let [lat, lon, alt, yaw, pitch, roll] = pose;
    let (sy, cy) = yaw.to_radians().sin_cos();
    let (sp, cp) = pitch.to_radians().sin_cos();
    let (sr, cr) = roll.to_radians().sin_cos();
    let [x, y, z] = offset;
    // Body → north-east-down: R = Rz(heading) · Ry(pitch) · Rx(roll).
    let n = cp * cy * x + (sr * sp * cy - cr * sy) * y + (cr * sp * cy + sr * sy) * z;
    let e = cp * sy * x + (sr * sp * sy + cr * cy) * y + (cr * sp * sy - sr * cy) * z;
    let d = -sp * x + sr * cp * y + cr * cp * z;
    LocalTangentPlane::new(Geodetic::new(lat, lon, alt)).enu_to_geodetic(DVec3::new(e, n, -d))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn entity_offsets_follow_heading_pitch_and_roll() {
        let at = [47.3, 11.4, 3000.0, 90.0, 0.0, 0.0];
        let ltp = LocalTangentPlane::new(Geodetic::new(47.3, 11.4, 3000.0));
        let enu = |g: Geodetic| ltp.geodetic_to_enu(g);
        // Heading east: forward is east, right is south, down is down.
        let fwd = enu(entity_relative(at, [100.0, 0.0, 0.0]));
        assert!((fwd - DVec3::new(100.0, 0.0, 0.0)).length() < 1e-6, "{fwd}");
        let right = enu(entity_relative(at, [0.0, 50.0, 0.0]));
        assert!(
            (right - DVec3::new(0.0, -50.0, 0.0)).length() < 1e-6,
            "{right}"
        );
        // Nose up 30° (heading north): forward climbs.
        let up = enu(entity_relative(
            [47.3, 11.4, 3000.0, 0.0, 30.0, 0.0],
            [100.0, 0.0, 0.0],
        ));
        assert!(
            (up - DVec3::new(0.0, 86.602_540_378, 50.0)).length() < 1e-6,
            "{up}"
        );
        // Right wing down 90° (heading north): body y points down.
        let wing = enu(entity_relative(
            [47.3, 11.4, 3000.0, 0.0, 0.0, 90.0],
            [0.0, 10.0, 0.0],
        ));
        assert!(
            (wing - DVec3::new(0.0, 0.0, -10.0)).length() < 1e-6,
            "{wing}"
        );
    }
}
