//! The entities of one frame as the GPU draws them (pure): the LOD decision across channels,
//! frustum culling for the channel drawn, one instance per drawn entity with its position
//! relative to the eye (subtracted in f64, then rounded to f32, as the terrain's tile origins
//! are) and its body axes, grouped so that each (model, level) is one instanced indirect draw.

use aerie_config::entities::LOD_LEVELS;
use aerie_terrain::camera::Camera;
use glam::{DMat3, DVec3};
use serde::Serialize;

use crate::render::entity_lod::{sphere_in_frustum, LodInput, LodParams, LodState, LodView};
use crate::render::gpu::{DrawIndexedIndirect, EntityInstance};
use crate::render::models::Model;

/// One entity to draw, in the renderer's world (local east-north-up metres).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EntityDraw {
    /// Entity ID (the LOD's hysteresis memory is per ID).
    pub id: u16,
    /// Index of its model in the library.
    pub model: usize,
    /// The model's origin, world metres.
    pub position: DVec3,
    /// Columns: the body x (forward), y (right), z (down) axes in world ENU.
    pub body_to_world: DMat3,
}

/// What a frame drew of the entities.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct EntityFrameStats {
    /// Entities handed to the renderer.
    pub known: u32,
    /// Drawn in this channel.
    pub drawn: u32,
    /// Not drawn: outside this channel's view.
    pub culled: u32,
    /// Instances per level (0 finest).
    pub instances_per_level: [u32; LOD_LEVELS],
    /// Triangles per level.
    pub triangles_per_level: [u64; LOD_LEVELS],
    /// Triangles had every drawn entity been drawn at level 0 (LOD off).
    pub triangles_without_lod: u64,
    /// Entities whose level changed this frame.
    pub lod_switches: u32,
    /// Indirect draws recorded (one per non-empty model and level).
    pub draws: u32,
    /// CPU time of the decisions and the instance build, µs.
    pub cpu_us: f64,
}

impl EntityFrameStats {
    /// Triangles drawn.
    pub fn triangles(&self) -> u64 {
        self.triangles_per_level.iter().sum()
    }
}

/// One frame's instances and draws.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct EntityFrame {
    /// Instances, grouped by (model, level) in the order of `draws`.
    pub instances: Vec<EntityInstance>,
    /// One command per non-empty (model, level); `first_instance` indexes `instances`.
    pub draws: Vec<DrawIndexedIndirect>,
    /// What it drew.
    pub stats: EntityFrameStats,
}

/// The bounding sphere of `e` (world centre, radius) with model scale `scale`.
pub fn sphere(models: &[Model], scale: f64, e: &EntityDraw) -> (DVec3, f64) {
    let m = &models[e.model.min(models.len() - 1)];
    let c = DVec3::from_array(m.centre.map(f64::from)) * scale;
    (
        e.position + e.body_to_world * c,
        f64::from(m.radius) * scale,
    )
}

/// Builds the frame drawn from `camera`: decides every entity's level over `views` (every
/// channel of the frame, or just this one), culls against `camera`, groups the instances.
/// `models` must not be empty (the library always holds the default model).
pub fn build_frame(
    models: &[Model],
    scale: f64,
    params: &LodParams,
    state: &mut LodState,
    entities: &[EntityDraw],
    views: &[LodView],
    camera: &Camera,
) -> EntityFrame {
    let inputs: Vec<LodInput> = entities
        .iter()
        .map(|e| {
            let (centre, radius) = sphere(models, scale, e);
            LodInput {
                id: e.id,
                centre,
                radius,
            }
        })
        .collect();
    let mut decisions = Vec::with_capacity(entities.len());
    let counts = state.decide(params, &inputs, views, &mut decisions);
    // Counting sort by (model, level): each group becomes one draw.
    let groups = models.len() * LOD_LEVELS;
    let mut keyed: Vec<(usize, &EntityDraw)> = Vec::with_capacity(entities.len());
    let mut stats = EntityFrameStats {
        known: entities.len() as u32,
        lod_switches: counts.switches as u32,
        ..EntityFrameStats::default()
    };
    let mut per_group = vec![0u32; groups];
    for ((e, d), input) in entities.iter().zip(&decisions).zip(&inputs) {
        let visible = d.level.is_some() && sphere_in_frustum(camera, input.centre, input.radius);
        let Some(level) = d.level.filter(|_| visible) else {
            stats.culled += 1;
            continue;
        };
        let model = e.model.min(models.len() - 1);
        let key = model * LOD_LEVELS + usize::from(level);
        per_group[key] += 1;
        keyed.push((key, e));
    }
    let mut first = vec![0u32; groups];
    let mut acc = 0u32;
    for (f, n) in first.iter_mut().zip(&per_group) {
        *f = acc;
        acc += n;
    }
    let mut instances = vec![EntityInstance::default_zeroed(); keyed.len()];
    let mut cursor = first.clone();
    for (key, e) in keyed {
        let m = &models[key / LOD_LEVELS];
        let rel = (e.position - camera.position).as_vec3();
        let axes = e.body_to_world;
        let t = m.tint;
        instances[cursor[key] as usize] = EntityInstance {
            offset_scale: [rel.x, rel.y, rel.z, scale as f32],
            axis_x: axes.x_axis.as_vec3().extend(t[0]).to_array(),
            axis_y: axes.y_axis.as_vec3().extend(t[1]).to_array(),
            axis_z: axes.z_axis.as_vec3().extend(t[2]).to_array(),
        };
        cursor[key] += 1;
    }
    let mut draws = Vec::new();
    for (key, &n) in per_group.iter().enumerate() {
        if n == 0 {
            continue;
        }
        let (m, level) = (&models[key / LOD_LEVELS], key % LOD_LEVELS);
        let range = m.levels[level];
        draws.push(DrawIndexedIndirect {
            index_count: range.index_count,
            instance_count: n,
            first_index: range.first_index,
            vertex_offset: m.vertex_offset,
            first_instance: first[key],
        });
        stats.drawn += n;
        stats.instances_per_level[level] += n;
        stats.triangles_per_level[level] += u64::from(n) * u64::from(range.triangles());
        stats.triangles_without_lod += u64::from(n) * u64::from(m.levels[0].triangles());
    }
    stats.draws = draws.len() as u32;
    EntityFrame {
        instances,
        draws,
        stats,
    }
}

impl EntityInstance {
    fn default_zeroed() -> Self {
        bytemuck::Zeroable::zeroed()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::models::{ModelLibrary, DEFAULT_MODEL};
    use aerie_terrain::camera::{Attitude, Frustum};

    fn camera() -> Camera {
        Camera::new(
            DVec3::new(1000.0, 2000.0, 500.0),
            Attitude::from_degrees(0.0, 0.0, 0.0),
            Frustum::symmetric(60f64.to_radians(), 256, 144),
        )
    }

    fn at(id: u16, model: usize, north_m: f64) -> EntityDraw {
        EntityDraw {
            id,
            model,
            position: camera().position + DVec3::new(0.0, north_m, 0.0),
            body_to_world: DMat3::IDENTITY,
        }
    }

    #[test]
    fn levels_group_into_one_draw_each_and_behind_the_eye_is_culled() {
        let lib = ModelLibrary::with_default();
        let cam = camera();
        let views = [LodView {
            camera: cam,
            viewport: (256, 144),
        }];
        // f = 128/tan(30°) ≈ 222 px; radius ≈ 5.9 m: 48 px at ≈ 27 m, 12 px at ≈ 109 m.
        let entities = [
            at(1, DEFAULT_MODEL, 20.0),
            at(2, DEFAULT_MODEL, 60.0),
            at(3, DEFAULT_MODEL, 500.0),
            at(4, DEFAULT_MODEL, 800.0),
            at(5, DEFAULT_MODEL, -300.0),
        ];
        let mut state = LodState::default();
        let f = build_frame(
            &lib.models,
            1.0,
            &LodParams::default(),
            &mut state,
            &entities,
            &views,
            &cam,
        );
        let s = f.stats;
        assert_eq!((s.known, s.drawn, s.culled), (5, 4, 1));
        assert_eq!(s.instances_per_level, [1, 1, 2]);
        assert_eq!(f.draws.len(), 3, "one draw per non-empty level");
        let levels = &lib.models[0].levels;
        assert_eq!(f.draws[2].instance_count, 2);
        assert_eq!(f.draws[2].index_count, levels[2].index_count);
        assert_eq!(f.draws[2].first_instance, 2);
        assert_eq!(
            s.triangles(),
            u64::from(levels[0].triangles() + levels[1].triangles() + 2 * levels[2].triangles())
        );
        assert_eq!(
            s.triangles_without_lod,
            4 * u64::from(levels[0].triangles())
        );
        // Camera-relative offsets: entity 4 is 800 m north of the eye, 2 km from the origin.
        assert!(f
            .instances
            .iter()
            .any(|i| i.offset_scale == [0.0, 800.0, 0.0, 1.0]));
        // Moving entity 1 back to 100 m drops it to level 1: one switch, then none.
        let mut moved = entities;
        moved[0] = at(1, DEFAULT_MODEL, 100.0);
        let f = build_frame(
            &lib.models,
            1.0,
            &LodParams::default(),
            &mut state,
            &moved,
            &views,
            &cam,
        );
        assert_eq!(f.stats.lod_switches, 1);
        assert_eq!(f.stats.instances_per_level, [0, 2, 2]);
    }
}

/// Figures for the report, not assertions (`cargo test -p aerie --lib entity_figures --
/// --ignored --nocapture`): CPU time of the decisions and the instance build for 500 and 1000
/// entities of 3 models over a 1280×720 view, and triangles with LOD on and off.
#[cfg(test)]
mod figures {
    use super::*;
    use crate::render::models::{default_aircraft, ModelLibrary};
    use aerie_terrain::camera::{Attitude, Frustum};

    #[test]
    #[ignore]
    fn entity_figures() {
        let mut lib = ModelLibrary::with_default();
        let big = {
            let mut m = default_aircraft();
            for p in &mut m.positions {
                *p = p.map(|c| c * 4.0);
            }
            m
        };
        lib.add_for_type(1, "default ×4".into(), &big);
        lib.add_for_type(2, "default again".into(), &default_aircraft());
        for m in &lib.models {
            let t: Vec<u32> = m.levels.iter().map(|l| l.triangles()).collect();
            let e: Vec<f32> = m.levels.iter().map(|l| l.error_m).collect();
            println!(
                "model {}: triangles {t:?}, error m {e:?}, radius {}",
                m.name, m.radius
            );
        }
        let cam = Camera::new(
            DVec3::new(0.0, 0.0, 1000.0),
            Attitude::from_degrees(0.0, -5.0, 0.0),
            Frustum::symmetric(60f64.to_radians(), 1280, 720),
        );
        let views = [LodView {
            camera: cam,
            viewport: (1280, 720),
        }];
        for n in [500usize, 1000] {
            // A loose formation: rows 60 m apart ahead of the eye, 3 models in turn.
            let entities: Vec<EntityDraw> = (0..n)
                .map(|i| EntityDraw {
                    id: i as u16,
                    model: i % 3,
                    position: DVec3::new(
                        (i % 25) as f64 * 60.0 - 720.0,
                        100.0 + (i / 25) as f64 * 60.0,
                        1000.0 + (i % 7) as f64 * 20.0 - 60.0,
                    ),
                    body_to_world: DMat3::IDENTITY,
                })
                .collect();
            let mut state = LodState::default();
            let mut us = Vec::new();
            let mut last = EntityFrame::default();
            for _ in 0..200 {
                let t0 = std::time::Instant::now();
                last = build_frame(
                    &lib.models,
                    1.0,
                    &LodParams::default(),
                    &mut state,
                    &entities,
                    &views,
                    &cam,
                );
                us.push(t0.elapsed().as_secs_f64() * 1e6);
            }
            us.sort_by(f64::total_cmp);
            let s = last.stats;
            println!(
                "{n} entities: median {:.0} µs, p99 {:.0} µs per frame; drawn {} culled {}; instances per level {:?}; triangles {} (LOD off {}); {} draws",
                us[us.len() / 2],
                us[us.len() * 99 / 100],
                s.drawn,
                s.culled,
                s.instances_per_level,
                s.triangles(),
                s.triangles_without_lod,
                s.draws
            );
        }
    }
}
