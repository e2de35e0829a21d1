//! A little-endian CDR encoder, the encoding ROS 2 records its messages in: for writing messages
//! of one's own, such as synthetic bags for tests and examples (with the `mcap` crate's writer).
//! Fields are appended in the order of the message definition; each is aligned to its size,
//! counted after the 4-byte encapsulation header, as ROS 2's serializer does.

/// One message being encoded. The methods append a field and return the writer, so that a
/// message reads as its definition: `w.header(t, "imu_link").f64(0.0)…`.
#[derive(Debug, Clone)]
pub struct CdrWriter {
    buf: Vec<u8>,
}

impl Default for CdrWriter {
    fn default() -> Self {
        Self::new()
    }
}

impl CdrWriter {
    /// An empty message: the encapsulation header of little-endian CDR only.
    #[must_use]
    pub fn new() -> Self {
        Self { buf: vec![0, 1, 0, 0] }
    }

    /// Back to an empty message, keeping the buffer (to write many messages without allocating).
    pub fn clear(&mut self) -> &mut Self {
        self.buf.truncate(4);
        self
    }

    fn align(&mut self, size: usize) {
        while (self.buf.len() - 4) % size != 0 {
            self.buf.push(0);
        }
    }

    /// A `uint8`, `int8` (as its bits), `bool` or `byte` field.
    pub fn u8(&mut self, v: u8) -> &mut Self {
        self.buf.push(v);
        self
    }

    /// A `uint16` field.
    pub fn u16(&mut self, v: u16) -> &mut Self {
        self.align(2);
        self.buf.extend_from_slice(&v.to_le_bytes());
        self
    }

    /// An `int32` field.
    pub fn i32(&mut self, v: i32) -> &mut Self {
        self.align(4);
        self.buf.extend_from_slice(&v.to_le_bytes());
        self
    }

    /// A `uint32` field (also a sequence's length).
    pub fn u32(&mut self, v: u32) -> &mut Self {
        self.align(4);
        self.buf.extend_from_slice(&v.to_le_bytes());
        self
    }

    /// A `float64` field.
    pub fn f64(&mut self, v: f64) -> &mut Self {
        self.align(8);
        self.buf.extend_from_slice(&v.to_le_bytes());
        self
    }

    /// A `string` field: its length with the terminating NUL, its bytes, the NUL.
    ///
    /// # Panics
    /// If `s` is longer than `u32::MAX - 1` bytes, which CDR cannot encode.
    pub fn string(&mut self, s: &str) -> &mut Self {
        let len = u32::try_from(s.len() + 1).expect("a CDR string is shorter than 4 GiB");
        self.u32(len);
        self.buf.extend_from_slice(s.as_bytes());
        self.buf.push(0);
        self
    }

    /// A `std_msgs/Header`: the stamp (`sec`, `nanosec`) of `stamp_ns` nanoseconds, and `frame_id`.
    pub fn header(&mut self, stamp_ns: u64, frame_id: &str) -> &mut Self {
        let sec = i32::try_from(stamp_ns / 1_000_000_000).unwrap_or(i32::MAX);
        self.i32(sec).u32((stamp_ns % 1_000_000_000) as u32).string(frame_id)
    }

    /// The encoded message.
    #[must_use]
    pub fn bytes(&self) -> &[u8] {
        &self.buf
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fields_are_aligned_after_the_encapsulation_header() {
        let mut w = CdrWriter::new();
        w.u8(7).f64(1.5).u16(3).string("ab").header(2_000_000_003, "f");
        let mut expected = vec![0, 1, 0, 0, 7, 0, 0, 0, 0, 0, 0, 0];
        expected.extend_from_slice(&1.5f64.to_le_bytes());
        expected.extend_from_slice(&[3, 0, 0, 0, 3, 0, 0, 0, b'a', b'b', 0, 0]);
        expected.extend_from_slice(&[2, 0, 0, 0, 3, 0, 0, 0, 2, 0, 0, 0, b'f', 0]);
        assert_eq!(w.bytes(), &expected[..]);
        assert_eq!(w.clear().bytes(), &[0, 1, 0, 0]);
    }
}
