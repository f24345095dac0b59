//! One `#[repr(C)]` + bytemuck definition per GPU struct, mirroring `shaders/gpu_types.glsl`.
//! The test below parses that GLSL file and checks every offset and size against the
//! std140 / std430 rules, so the two sides cannot drift apart.

use bytemuck::{Pod, Zeroable};

/// Uniform block (std140), one per frame.
#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable)]
pub struct FrameUniforms {
    pub relative_world_to_clip: [[f32; 4]; 4],
    pub sun_dir: [f32; 4],
    pub sky_colour: [f32; 4],
    pub grid_spacing: [f32; 4],
    pub grid_size: [i32; 4],
    pub clipmap: [i32; 4],
    pub eye_world: [f32; 4],
    pub sun_colour: [f32; 4],
    pub ambient_colour: [f32; 4],
    pub sky_sun: [f32; 4],
    pub perez_a: [f32; 4],
    pub perez_b: [f32; 4],
    pub perez_c: [f32; 4],
    pub perez_d: [f32; 4],
    pub perez_e: [f32; 4],
    pub sky_zenith: [f32; 4],
    /// x: streamed imagery levels (0: none), y: texels per level sample k, z: window side.
    pub imagery_stream: [i32; 4],
    /// Per streamed level: its window's first texel (x, y, absolute on the level's raster)
    /// and z = 1 when every cell of it is filled (render/imagery_stream.rs).
    pub imagery_regions: [[i32; 4]; IMAGERY_STREAM_LEVELS],
}

/// Streamed imagery levels the frame uniforms have room for (`imagery_regions`; the GLSL
/// array's length in shaders/gpu_types.glsl).
pub const IMAGERY_STREAM_LEVELS: usize = 12;

/// Storage buffer element (std430), one per drawn tile: 144 bytes. A projected grid's node
/// polynomials travel apart ([`GeoPolynomial`], a parallel buffer written only for such grids),
/// so a geographic or flat frame stages and copies a third of the bytes.
#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable, PartialEq)]
pub struct TileInstance {
    pub origin_rel: [f32; 2],
    pub origin_sample: [i32; 2],
    pub step: u32,
    pub level: u32,
    pub refinement: u32,
    pub slot: u32,
    pub skirt_m: f32,
    pub slot_x: u32,
    pub slot_y: u32,
    pub slot_stride: u32,
    pub morph: [f32; 4],
    pub geo_origin: [f32; 4],
    pub geo_axis_r: [f32; 4],
    pub geo_axis_t: [f32; 4],
    pub geo_axis_z: [f32; 4],
    pub geo_radius: [f32; 4],
}

/// A projected (UTM) node's cubic polynomials (std430, `shaders/gpu_types.glsl`
/// `GeoPolynomial`): element i of the polynomial buffer belongs to tile instance i. Only a
/// projected grid's frames stage them.
#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable, PartialEq, Default)]
pub struct GeoPolynomial {
    pub geo_s: [[f32; 4]; 9],
    pub geo_n: [[f32; 4]; 10],
}

impl GeoPolynomial {
    /// The polynomials of `fields` (zero on a geographic grid).
    pub fn of(fields: &GeoFields) -> Self {
        GeoPolynomial {
            geo_s: fields.geo_s,
            geo_n: fields.geo_n,
        }
    }
}

/// A node's place on the WGS84 ellipsoid (`shaders/gpu_types.glsl` `GeoFields`, std430; see
/// `render/geo_instances.rs`): the tail of [`TileInstance`], and one record per base-mesh cell
/// of the tessellation baseline. All zero on the flat path (`geo_origin.w == 0` tells the
/// shader so).
#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable, PartialEq, Default)]
pub struct GeoFields {
    pub geo_origin: [f32; 4],
    pub geo_axis_r: [f32; 4],
    pub geo_axis_t: [f32; 4],
    pub geo_axis_z: [f32; 4],
    pub geo_radius: [f32; 4],
    pub geo_s: [[f32; 4]; 9],
    pub geo_n: [[f32; 4]; 10],
}

/// `VkDrawIndexedIndirectCommand`, as the device reads it (a Pod twin of ash's struct).
#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable, PartialEq, Eq, Default)]
pub struct DrawIndexedIndirect {
    pub index_count: u32,
    pub instance_count: u32,
    pub first_index: u32,
    pub vertex_offset: i32,
    pub first_instance: u32,
}

/// One model vertex (std430), in the model's body axes: see `shaders/gpu_types.glsl`.
#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable, PartialEq)]
pub struct EntityVertex {
    pub position: [f32; 4],
    pub normal: [f32; 4],
}

/// One drawn entity (std430), read as per-instance vertex attributes.
#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable, PartialEq)]
pub struct EntityInstance {
    pub offset_scale: [f32; 4],
    pub axis_x: [f32; 4],
    pub axis_y: [f32; 4],
    pub axis_z: [f32; 4],
}

/// Push constants of the entity pipeline (std430 as push constants are laid out).
#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable, PartialEq)]
pub struct EntityPush {
    pub relative_world_to_clip: [[f32; 4]; 4],
    pub sun_dir: [f32; 4],
    pub sky_colour: [f32; 4],
}

/// Push constants of the GPU normal pass (std430 as push constants are laid out): one job of
/// `render/normal_pass.rs`, see `shaders/gpu_types.glsl`.
#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable, PartialEq)]
pub struct NormalPush {
    pub origin: [i32; 2],
    pub size: [u32; 2],
    pub region_lo: [i32; 2],
    pub region_hi: [i32; 2],
    pub texel_lo: [u32; 2],
    pub spacing: [f32; 2],
    pub layer: u32,
    pub side: u32,
    pub offset: u32,
    pub pad: u32,
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::mem::{offset_of, size_of};

    #[derive(Clone, Copy, PartialEq)]
    enum Rules {
        Std140,
        Std430,
    }

    /// (size, base alignment) of a GLSL type under the given rules.
    fn type_layout(ty: &str, rules: Rules) -> (usize, usize) {
        let (size, align) = match ty {
            "float" | "int" | "uint" => (4, 4),
            "vec2" | "ivec2" | "uvec2" => (8, 8),
            "vec3" | "ivec3" | "uvec3" => (12, 16),
            "vec4" | "ivec4" | "uvec4" => (16, 16),
            // Column-major: 4 columns of vec4.
            "mat4" => (64, 16),
            other => panic!("type {other} not handled by the layout test"),
        };
        let _ = rules; // no arrays or nested structs yet: both rules agree on these types
        (size, align)
    }

    /// Offsets of each field and the struct size, per the GLSL rules, from the GLSL source.
    fn glsl_struct(name: &str, rules: Rules) -> (Vec<(String, usize)>, usize) {
        let src = include_str!("../../../shaders/gpu_types.glsl");
        let start = src
            .find(&format!("struct {name} {{"))
            .unwrap_or_else(|| panic!("struct {name} not in gpu_types.glsl"));
        let body = &src[start..];
        let body = &body[body.find('{').unwrap() + 1..body.find("};").unwrap()];
        let mut offset: usize = 0;
        let mut max_align = 4;
        let mut fields = Vec::new();
        for line in body.lines() {
            let code = line.split("//").next().unwrap().trim();
            if code.is_empty() {
                continue;
            }
            let code = code.trim_end_matches(';');
            let mut parts = code.split_whitespace();
            let (ty, field) = (parts.next().unwrap(), parts.next().unwrap());
            let (size, align) = type_layout(ty, rules);
            // `name[n]`: an array of n elements, each padded to its alignment (vec4 here).
            let (field, size) = match field.split_once('[') {
                Some((name, n)) => {
                    let n: usize = n.trim_end_matches(']').parse().unwrap();
                    (name, n * size.div_ceil(align) * align)
                }
                None => (field, size),
            };
            offset = offset.div_ceil(align) * align;
            fields.push((field.to_string(), offset));
            offset += size;
            max_align = max_align.max(align);
        }
        // std140 rounds a struct's alignment up to 16; std430 does not.
        if rules == Rules::Std140 {
            max_align = max_align.max(16);
        }
        (fields, offset.div_ceil(max_align) * max_align)
    }

    macro_rules! check {
        ($ty:ident, $rules:expr, [$($field:ident),*]) => {{
            let (fields, size) = glsl_struct(stringify!($ty), $rules);
            let rust: Vec<(String, usize)> = vec![$((stringify!($field).to_string(), offset_of!($ty, $field))),*];
            assert_eq!(fields, rust, "field names/offsets of {}", stringify!($ty));
            assert_eq!(size, size_of::<$ty>(), "size of {}", stringify!($ty));
        }};
    }

    #[test]
    fn frame_uniforms_match_glsl_std140() {
        check!(
            FrameUniforms,
            Rules::Std140,
            [
                relative_world_to_clip,
                sun_dir,
                sky_colour,
                grid_spacing,
                grid_size,
                clipmap,
                eye_world,
                sun_colour,
                ambient_colour,
                sky_sun,
                perez_a,
                perez_b,
                perez_c,
                perez_d,
                perez_e,
                sky_zenith,
                imagery_stream,
                imagery_regions
            ]
        );
    }

    #[test]
    fn tile_instance_matches_glsl_std430() {
        check!(
            TileInstance,
            Rules::Std430,
            [
                origin_rel,
                origin_sample,
                step,
                level,
                refinement,
                slot,
                skirt_m,
                slot_x,
                slot_y,
                slot_stride,
                morph,
                geo_origin,
                geo_axis_r,
                geo_axis_t,
                geo_axis_z,
                geo_radius
            ]
        );
    }

    #[test]
    fn geo_fields_match_glsl_std430_and_the_tile_instance_tail() {
        check!(
            GeoFields,
            Rules::Std430,
            [geo_origin, geo_axis_r, geo_axis_t, geo_axis_z, geo_radius, geo_s, geo_n]
        );
        check!(GeoPolynomial, Rules::Std430, [geo_s, geo_n]);
        // terrain.vert builds a GeoFields from the instance's tail and its polynomial: the
        // tail is GeoFields up to its polynomials, which are GeoPolynomial.
        let tail = offset_of!(TileInstance, geo_origin);
        assert_eq!(
            size_of::<TileInstance>() - tail,
            offset_of!(GeoFields, geo_s)
        );
        assert_eq!(
            offset_of!(TileInstance, geo_radius) - tail,
            offset_of!(GeoFields, geo_radius)
        );
        assert_eq!(
            size_of::<GeoFields>() - offset_of!(GeoFields, geo_s),
            size_of::<GeoPolynomial>()
        );
        assert_eq!(size_of::<TileInstance>(), 144);
    }

    #[test]
    fn layout_rules_catch_misplaced_fields() {
        // The checker itself: a vec3 followed by a float packs into 16 bytes, a vec2 after a
        // float is pushed to offset 8, and std140 rounds the struct to 16.
        assert_eq!(type_layout("vec3", Rules::Std430), (12, 16));
        let (fields, size) = glsl_struct("TileInstance", Rules::Std140);
        assert_eq!(fields[1], ("origin_sample".to_string(), 8));
        assert_eq!(size % 16, 0);
    }

    #[test]
    fn entity_structs_match_glsl_std430() {
        check!(EntityVertex, Rules::Std430, [position, normal]);
        check!(
            EntityInstance,
            Rules::Std430,
            [offset_scale, axis_x, axis_y, axis_z]
        );
        check!(
            EntityPush,
            Rules::Std430,
            [relative_world_to_clip, sun_dir, sky_colour]
        );
    }

    #[test]
    fn normal_push_matches_glsl_std430() {
        check!(
            NormalPush,
            Rules::Std430,
            [origin, size, region_lo, region_hi, texel_lo, spacing, layer, side, offset, pad]
        );
    }

    #[test]
    fn indirect_command_matches_vulkan() {
        use ash::vk::DrawIndexedIndirectCommand as Vk;
        assert_eq!(size_of::<DrawIndexedIndirect>(), size_of::<Vk>());
        assert_eq!(
            offset_of!(DrawIndexedIndirect, index_count),
            offset_of!(Vk, index_count)
        );
        assert_eq!(
            offset_of!(DrawIndexedIndirect, instance_count),
            offset_of!(Vk, instance_count)
        );
        assert_eq!(
            offset_of!(DrawIndexedIndirect, first_index),
            offset_of!(Vk, first_index)
        );
        assert_eq!(
            offset_of!(DrawIndexedIndirect, vertex_offset),
            offset_of!(Vk, vertex_offset)
        );
        assert_eq!(
            offset_of!(DrawIndexedIndirect, first_instance),
            offset_of!(Vk, first_instance)
        );
    }
}
