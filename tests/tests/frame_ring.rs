//! The per-frame ring on lavapipe with the validation layer on: a frame abandoned after its
//! recording began (an error between `begin_recording` and `submit`, e.g. a staging overflow)
//! must not leave a fence that nothing signals — the next use of that frame and the ring's
//! teardown would otherwise wait forever.

use std::sync::mpsc;
use std::time::Duration;

use ash::vk;

use aerie::vk::frame_context::FrameRing;
use aerie::vk::{Device, DeviceDesc, Instance, FRAMES_IN_FLIGHT};
use aerie_tests::assert_validation_clean;

/// Runs `f` on its own thread and fails the test when it has not returned within `limit`
/// (a hang here is the bug, and a test that hangs tells nothing).
fn within(limit: Duration, f: impl FnOnce() + Send + 'static) {
    let (tx, rx) = mpsc::channel();
    std::thread::spawn(move || {
        f();
        let _ = tx.send(());
    });
    rx.recv_timeout(limit)
        .expect("the frame ring blocked: an abandoned frame's fence was never signalled");
}

#[test]
fn a_frame_abandoned_while_recording_neither_blocks_the_ring_nor_its_teardown() {
    within(Duration::from_secs(120), || {
        let mut instance = Instance::new(true).expect("instance");
        let counters = instance.counters();
        let mut device = Device::new(&instance, &DeviceDesc::default()).expect("device");
        let sizes = [vk::DescriptorPoolSize {
            ty: vk::DescriptorType::UNIFORM_BUFFER,
            descriptor_count: 4,
        }];
        let mut ring = FrameRing::new(&device, 1 << 16, 4, &sizes).expect("ring");
        // Abandon the first frame after its recording began, as an error path would.
        {
            let mut frame = ring.begin_frame(&device).expect("begin");
            let _cmd = frame.begin_recording(&device).expect("record");
        }
        // Every frame of the ring, the abandoned one included, is begun, recorded, submitted
        // and waited for, twice round.
        for _ in 0..2 * FRAMES_IN_FLIGHT + 1 {
            let mut frame = ring.begin_frame(&device).expect("begin after abandon");
            let _cmd = frame.begin_recording(&device).expect("record");
            let submitted = frame.submit(&device).expect("submit");
            ring.wait(&device, submitted).expect("wait");
        }
        // Abandoned again, then torn down: teardown waits on every fence.
        {
            let mut frame = ring.begin_frame(&device).expect("begin");
            let _cmd = frame.begin_recording(&device).expect("record");
        }
        ring.destroy(&device);
        device.destroy();
        instance.destroy();
        assert_validation_clean(&counters);
    });
}
