//! The validation plumbing itself: a deliberate API misuse is counted, so "zero messages" in the
//! other GPU tests means something.

use aerie::vk::{Device, DeviceDesc, Instance};
use ash::vk;

#[test]
fn validation_layer_counts_a_deliberate_error() {
    let mut instance = Instance::new(true).expect("instance with validation");
    let mut device = Device::new(&instance, &DeviceDesc::default()).expect("device");
    let counters = instance.counters();
    assert_eq!(counters.errors(), 0);
    // VUID-VkBufferCreateInfo-size-00912: size must be greater than 0.
    let info = vk::BufferCreateInfo::default()
        .size(0)
        .usage(vk::BufferUsageFlags::TRANSFER_SRC);
    // The invalid size is the point (the layer must report it), and a buffer the driver made anyway
    // is destroyed at once, before the device.
    // SAFETY: `device` is live.
    if let Ok(b) = unsafe { device.raw.create_buffer(&info, None) } {
        // SAFETY: `b` was created by `device` above and is used by nothing.
        unsafe { device.raw.destroy_buffer(b, None) };
    }
    assert!(
        counters.errors() >= 1,
        "the layer did not report a zero-sized buffer"
    );
    assert!(
        counters.messages().iter().any(|m| m.contains("00912")),
        "{:?}",
        counters.messages()
    );
    device.destroy();
    instance.destroy();
}

#[test]
fn leaked_object_is_reported_at_teardown() {
    let mut instance = Instance::new(true).expect("instance with validation");
    let mut device = Device::new(&instance, &DeviceDesc::default()).expect("device");
    let counters = instance.counters();
    let info = vk::SamplerCreateInfo::default();
    // SAFETY: `device` is live and the create info valid; leaking the sampler is the point.
    let _leaked = unsafe { device.raw.create_sampler(&info, None) }.unwrap();
    device.destroy(); // without destroying the sampler
    instance.destroy();
    assert!(
        counters.errors() >= 1,
        "a leaked sampler must be reported: {:?}",
        counters.messages()
    );
}
