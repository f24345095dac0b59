//! Bounds-checked field access in either byte order. Every read returns `None` past the end of
//! the buffer instead of panicking, so decoders stay panic-free on arbitrary input.

/// Byte order of a message on the wire.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ByteOrder {
    /// Least significant byte first (x86, ARM hosts).
    Little,
    /// Most significant byte first ("network byte order").
    Big,
}

/// Read-only view of a packet in a given byte order.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Rd<'a> {
    buf: &'a [u8],
    order: ByteOrder,
}

impl<'a> Rd<'a> {
    pub(crate) fn new(buf: &'a [u8], order: ByteOrder) -> Self {
        Self { buf, order }
    }

    pub(crate) fn bytes<const N: usize>(&self, off: usize) -> Option<[u8; N]> {
        let end = off.checked_add(N)?;
        self.buf.get(off..end)?.try_into().ok()
    }

    pub(crate) fn u8(&self, off: usize) -> Option<u8> {
        self.buf.get(off).copied()
    }

    pub(crate) fn u16(&self, off: usize) -> Option<u16> {
        let b = self.bytes::<2>(off)?;
        Some(match self.order {
            ByteOrder::Little => u16::from_le_bytes(b),
            ByteOrder::Big => u16::from_be_bytes(b),
        })
    }

    pub(crate) fn u32(&self, off: usize) -> Option<u32> {
        let b = self.bytes::<4>(off)?;
        Some(match self.order {
            ByteOrder::Little => u32::from_le_bytes(b),
            ByteOrder::Big => u32::from_be_bytes(b),
        })
    }

    pub(crate) fn u64(&self, off: usize) -> Option<u64> {
        let b = self.bytes::<8>(off)?;
        Some(match self.order {
            ByteOrder::Little => u64::from_le_bytes(b),
            ByteOrder::Big => u64::from_be_bytes(b),
        })
    }

    pub(crate) fn f32(&self, off: usize) -> Option<f32> {
        self.u32(off).map(f32::from_bits)
    }

    pub(crate) fn f64(&self, off: usize) -> Option<f64> {
        self.u64(off).map(f64::from_bits)
    }
}

/// Append-only writer in a given byte order (encoders build fixed-size packets with it).
#[derive(Debug)]
pub(crate) struct Wr {
    pub(crate) buf: Vec<u8>,
    order: ByteOrder,
}

impl Wr {
    pub(crate) fn new(order: ByteOrder, capacity: usize) -> Self {
        Self {
            buf: Vec::with_capacity(capacity),
            order,
        }
    }

    pub(crate) fn raw(&mut self, b: &[u8]) -> &mut Self {
        self.buf.extend_from_slice(b);
        self
    }

    pub(crate) fn u8(&mut self, v: u8) -> &mut Self {
        self.buf.push(v);
        self
    }

    pub(crate) fn u16(&mut self, v: u16) -> &mut Self {
        match self.order {
            ByteOrder::Little => self.raw(&v.to_le_bytes()),
            ByteOrder::Big => self.raw(&v.to_be_bytes()),
        }
    }

    pub(crate) fn u32(&mut self, v: u32) -> &mut Self {
        match self.order {
            ByteOrder::Little => self.raw(&v.to_le_bytes()),
            ByteOrder::Big => self.raw(&v.to_be_bytes()),
        }
    }

    pub(crate) fn u64(&mut self, v: u64) -> &mut Self {
        match self.order {
            ByteOrder::Little => self.raw(&v.to_le_bytes()),
            ByteOrder::Big => self.raw(&v.to_be_bytes()),
        }
    }

    pub(crate) fn f32(&mut self, v: f32) -> &mut Self {
        self.u32(v.to_bits())
    }

    pub(crate) fn f64(&mut self, v: f64) -> &mut Self {
        self.u64(v.to_bits())
    }

    /// The bytes as a fixed-size array; `N` must equal the written length (encoders' invariant).
    pub(crate) fn finish<const N: usize>(self) -> [u8; N] {
        let mut out = [0u8; N];
        let n = self.buf.len().min(N);
        out[..n].copy_from_slice(&self.buf[..n]);
        debug_assert_eq!(self.buf.len(), N, "encoder wrote the wrong number of bytes");
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_past_the_end_are_none() {
        let b = [1u8, 2, 3];
        let r = Rd::new(&b, ByteOrder::Little);
        assert_eq!(r.u16(1), Some(0x0302));
        assert_eq!(r.u16(2), None);
        assert_eq!(r.u32(0), None);
        assert_eq!(r.u64(usize::MAX - 2), None);
        assert_eq!(Rd::new(&b, ByteOrder::Big).u16(0), Some(0x0102));
    }

    #[test]
    fn writer_orders_bytes() {
        let mut w = Wr::new(ByteOrder::Big, 6);
        w.u16(0x8000).u32(0x0102_0304);
        assert_eq!(w.finish::<6>(), [0x80, 0, 1, 2, 3, 4]);
        let mut w = Wr::new(ByteOrder::Little, 2);
        w.u16(0x8000);
        assert_eq!(w.finish::<2>(), [0, 0x80]);
    }
}
