//! Carrying out upload jobs: copying the samples the plan gathered from its source into the
//! staging region (in the plan's order: strips, then pool uploads), recording the copies into
//! the height textures, and streaming uploads larger than one frame's budget over several
//! submissions (the first fill of a dataset, a spill after a jump, the index buffer).

use ash::vk;

use aerie_terrain::select::MAX_REFINEMENT;

use crate::render::gathered::SampleCursor;
use crate::render::gpu::FrameUniforms;
use crate::render::jobs::ImageUpload;
use crate::render::jobs::{staging_to_hold, PlanError, StagingBudget};
use crate::render::normal_map::NormalTexel;
use crate::render::overlay_pass::Panel;
use crate::render::plan::FramePlan;
use crate::vk::access::{image_barrier, memory_barrier, Access};
use crate::vk::conv::map_texel_copy;
use crate::vk::frame_context::{FrameContext, FrameRing};
use crate::vk::staging::StagingRing;
use crate::vk::{Device, VkError};

/// Where a sampled texture rests between uploads (heights in the vertex shader, normal maps in
/// the fragment shader, heights in the GPU normal pass: `render/normal_pass.rs`).
pub const SAMPLED: [Access; 3] = [
    Access::VertexShaderReadSampledImage,
    Access::FragmentShaderReadSampledImage,
    Access::ComputeShaderReadSampledImage,
];

/// `--normals gpu`: records the normal pass of a submission's level uploads after their heights'
/// copies (`render/normal_pass.rs`).
pub type GpuNormals<'r> =
    dyn FnMut(&mut FrameContext, vk::CommandBuffer, &[ImageUpload]) -> Result<(), VkError> + 'r;
const COPY_DST: [Access; 1] = [Access::TransferWrite];

/// Copies one upload's gathered samples (the cursor's next) into the open staging region;
/// returns its copy region.
pub fn stage_samples(
    staging: &mut StagingRing,
    samples: &mut SampleCursor,
    job: &ImageUpload,
) -> Result<vk::BufferImageCopy, VkError> {
    let Some(src) = samples.next(job) else {
        return Err(VkError::Other(format!(
            "the plan gathered fewer samples than its uploads need ({} left for {}×{})",
            samples.left(),
            job.size[0],
            job.size[1]
        )));
    };
    let (offset, bytes) = staging.alloc(job.bytes(), 4)?;
    bytes.copy_from_slice(bytemuck::cast_slice(src));
    Ok(buffer_image_copy(offset, job))
}

/// Copies one level strip's normal texels (the cursor's next) into the open staging region;
/// returns its copy region (into the normal texture, same texels and layer as the heights).
pub fn stage_normals(
    staging: &mut StagingRing,
    normals: &mut SampleCursor<NormalTexel>,
    job: &ImageUpload,
) -> Result<vk::BufferImageCopy, VkError> {
    let Some(src) = normals.next(job) else {
        return Err(VkError::Other(format!(
            "the plan computed fewer normal texels than its strips need ({} left for {}×{})",
            normals.left(),
            job.size[0],
            job.size[1]
        )));
    };
    let bytes = src.len() as u64 * crate::render::normal_map::NORMAL_TEXEL_BYTES;
    let (offset, out) = staging.alloc(bytes, 4)?;
    out.copy_from_slice(bytemuck::cast_slice(src));
    Ok(buffer_image_copy(offset, job))
}

/// The copy of `job`, staged at `offset`, into its texel rectangle and layer.
pub fn buffer_image_copy(offset: u64, job: &ImageUpload) -> vk::BufferImageCopy {
    map_texel_copy(offset, 0, job.layer, job.texel, job.size)
}

/// Copies staged regions into a sampled texture: SHADER_READ_ONLY → TRANSFER_DST (contents kept,
/// after earlier frames' vertex-shader reads), the copies, then back to SHADER_READ_ONLY.
pub fn record_image_copies(
    device: &Device,
    cmd: vk::CommandBuffer,
    staging: vk::Buffer,
    image: vk::Image,
    copies: &[vk::BufferImageCopy],
) {
    if copies.is_empty() {
        return;
    }
    let colour = vk::ImageAspectFlags::COLOR;
    image_barrier(device, cmd, image, colour, &SAMPLED, &COPY_DST, false);
    // `image` is live and in TRANSFER_DST_OPTIMAL after the barrier; every region was staged inside
    // `staging` by `stage_samples` and lies inside the image (the plan's texel rectangles are within
    // the texture side and its layers).
    // SAFETY: `cmd` is recording.
    unsafe {
        device.raw.cmd_copy_buffer_to_image(
            cmd,
            staging,
            image,
            vk::ImageLayout::TRANSFER_DST_OPTIMAL,
            copies,
        )
    };
    image_barrier(device, cmd, image, colour, &COPY_DST, &SAMPLED, false);
}

/// Moves every texture from nothing into SHADER_READ_ONLY, the layout it rests in between
/// uploads, in one submission.
pub fn initialise_images(
    device: &Device,
    ring: &mut FrameRing,
    images: impl IntoIterator<Item = vk::Image>,
) -> Result<(), VkError> {
    let mut frame = ring.begin_frame(device)?;
    let cmd = frame.begin_recording(device)?;
    for image in images {
        let colour = vk::ImageAspectFlags::COLOR;
        image_barrier(
            device,
            cmd,
            image,
            colour,
            &[Access::Nothing],
            &SAMPLED,
            true,
        );
    }
    let _in_flight = frame.submit(device)?;
    Ok(())
}

/// Uploads bytes into a device buffer read as indices and by vertex shaders, in as many
/// submissions as the per-frame budget requires.
pub fn stream_buffer(
    device: &Device,
    ring: &mut FrameRing,
    bytes: &[u8],
    dst: vk::Buffer,
) -> Result<(), VkError> {
    let chunk = (ring.staging_budget() / 2).max(4) / 4 * 4;
    let mut done = 0usize;
    while done < bytes.len() {
        let n = (bytes.len() - done).min(chunk as usize);
        let mut frame = ring.begin_frame(device)?;
        let offset = frame.staging().push(&bytes[done..done + n], 4)?;
        let src = frame.staging_buffer();
        let cmd = frame.begin_recording(device)?;
        let region = vk::BufferCopy {
            src_offset: offset,
            dst_offset: done as u64,
            size: n as u64,
        };
        // `n` bytes were staged at `offset` of the live staging buffer, and `dst` (live,
        // TRANSFER_DST) is at least `bytes.len()` long (the caller's).
        // SAFETY: `cmd` is recording.
        unsafe { device.raw.cmd_copy_buffer(cmd, src, dst, &[region]) };
        memory_barrier(
            device,
            cmd,
            &[Access::TransferWrite],
            &[Access::IndexBuffer, Access::VertexShaderReadStorageBuffer],
        );
        let _in_flight = frame.submit(device)?;
        done += n;
    }
    Ok(())
}

/// Streams level-texture uploads into `image`, one submission per inner list (as the plan split
/// them), each job's normal texels after its heights into the normal texture when `normals`
/// (staged), or computed after the copies by `gpu_normals`. Returns the submission count.
pub fn stream_image_uploads(
    device: &Device,
    ring: &mut FrameRing,
    samples: &mut SampleCursor,
    image: vk::Image,
    mut normals: Option<(vk::Image, &mut SampleCursor<NormalTexel>)>,
    mut gpu_normals: Option<&mut GpuNormals>,
    submissions: &[Vec<ImageUpload>],
) -> Result<u32, VkError> {
    for jobs in submissions {
        let mut frame = ring.begin_frame(device)?;
        let mut copies = Vec::with_capacity(jobs.len());
        let mut normal_copies = Vec::new();
        for job in jobs {
            copies.push(stage_samples(frame.staging(), samples, job)?);
            if let Some((_, cursor)) = normals.as_mut() {
                normal_copies.push(stage_normals(frame.staging(), cursor, job)?);
            }
        }
        let src = frame.staging_buffer();
        let cmd = frame.begin_recording(device)?;
        record_image_copies(device, cmd, src, image, &copies);
        if let Some((normal_image, _)) = normals.as_ref() {
            record_image_copies(device, cmd, src, *normal_image, &normal_copies);
        }
        if let Some(pass) = gpu_normals.as_mut() {
            pass(&mut frame, cmd, jobs)?;
        }
        let _in_flight = frame.submit(device)?;
    }
    Ok(submissions.len() as u32)
}

/// Where a frame's plan landed in its staging region.
pub struct StagedFrame {
    pub strip_copies: Vec<vk::BufferImageCopy>,
    /// The strips' normal texels, into the normal texture (empty without normal maps).
    pub normal_copies: Vec<vk::BufferImageCopy>,
    /// Copies per pool r = 1..=MAX_REFINEMENT (index r − 1), in the plan's order.
    pub pool_copies: Vec<Vec<vk::BufferImageCopy>>,
    pub uniforms: u64,
    pub draws: u64,
    /// None when nothing is drawn.
    pub instances: Option<u64>,
    /// None unless a projected grid's nodes are drawn.
    pub polynomials: Option<u64>,
    /// None without an overlay (or an empty one).
    pub overlay: Option<u64>,
}

/// Stages everything `plan` says, in its order — strips, pool uploads, uniforms, indirect
/// commands, instances, polynomials, overlay — into the frame's open region (the uploads' samples from
/// `samples`, which must then be spent), and checks that it took exactly the bytes the plan
/// counted (so the plan's budget decisions were about this region).
pub fn stage_frame(
    staging: &mut StagingRing,
    samples: &mut SampleCursor,
    normals: &mut SampleCursor<NormalTexel>,
    plan: &FramePlan,
    uniforms: &FrameUniforms,
    overlay: Option<&Panel>,
) -> Result<StagedFrame, VkError> {
    let mut strip_copies = Vec::with_capacity(plan.strips.len());
    let mut normal_copies = Vec::new();
    for job in &plan.strips {
        strip_copies.push(stage_samples(staging, samples, job)?);
        if plan.normal_maps {
            normal_copies.push(stage_normals(staging, normals, job)?);
        }
    }
    let mut pool_copies = vec![Vec::new(); MAX_REFINEMENT as usize];
    for p in &plan.pool_uploads {
        let copy = stage_samples(staging, samples, &p.upload)?;
        pool_copies[p.key.refinement as usize - 1].push(copy);
    }
    if samples.left() != 0 || normals.left() != 0 {
        return Err(VkError::Other(format!(
            "the plan gathered {} samples and {} normal texels more than its uploads staged",
            samples.left(),
            normals.left()
        )));
    }
    let uniforms = staging.push(std::slice::from_ref(uniforms), 16)?;
    let draws = staging.push(&plan.draws, 4)?;
    let instances = if plan.instances.is_empty() {
        None
    } else {
        Some(staging.push(&plan.instances, 16)?)
    };
    let polynomials = if plan.polynomials.is_empty() {
        None
    } else {
        Some(staging.push(&plan.polynomials, 16)?)
    };
    let overlay = match overlay {
        Some(p) if p.bytes() > 0 => Some(staging.push(&p.rgba, 16)?),
        _ => None,
    };
    if staging.used() != plan.staged_bytes {
        return Err(VkError::Staging(format!(
            "staging the frame took {} bytes, its plan counted {}",
            staging.used(),
            plan.staged_bytes
        )));
    }
    Ok(StagedFrame {
        strip_copies,
        normal_copies,
        pool_copies,
        uniforms,
        draws,
        instances,
        polynomials,
        overlay,
    })
}

/// Grows `ring`'s staging region when the frame's fixed pushes (`reserve` bytes: its instance
/// records) would crowd it (`jobs::staging_to_hold`, for the configured `upload_budget`);
/// the frame's new budget when it grew. Call with no frame context open.
pub fn fit_staging(
    ring: &mut FrameRing,
    d: &Device,
    upload_budget: u64,
    reserve: u64,
) -> Result<Option<StagingBudget>, VkError> {
    let Some(grown) = staging_to_hold(ring.staging_budget(), upload_budget, reserve) else {
        return Ok(None);
    };
    Ok(ring
        .grow_staging(d, grown)?
        .then(|| StagingBudget::new(ring.staging_budget(), ring.staging_alignment())))
}

/// A plan that cannot be carried out fails the frame with its reason.
impl From<PlanError> for VkError {
    fn from(e: PlanError) -> Self {
        match e {
            PlanError::Staging(m) => VkError::Staging(m),
            PlanError::Other(m) => VkError::Other(m),
        }
    }
}
