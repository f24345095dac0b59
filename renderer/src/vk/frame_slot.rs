//! The proof that a frame in flight may reuse its resources: every per-frame owner (staging
//! region, descriptor pool, timestamp queries) takes a [`SignalledFrame`] instead of an index, so
//! "only after that frame's fence signalled" is a type, not a comment.

/// Frame in flight `index`, whose fence has signalled since its last submission: the GPU no
/// longer reads or writes anything that frame used.
///
/// Only the frame ring creates one (`FrameRing::begin_frame` and `FrameRing::wait`, after
/// waiting for the fence), it is neither `Clone` nor `Copy`, and submitting the frame consumes
/// the context that holds it — so a holder can never see a frame that is in flight again.
#[derive(Debug)]
pub struct SignalledFrame {
    index: usize,
}

impl SignalledFrame {
    /// Call only once the fence of frame `index` has been waited for (and nothing submitted on
    /// it since).
    pub(in crate::vk) fn after_fence_wait(index: usize) -> Self {
        Self { index }
    }

    /// The frame-in-flight index (`0..FRAMES_IN_FLIGHT`): which region, pool or query range.
    pub fn index(&self) -> usize {
        self.index
    }
}
