//! A little-endian CDR encoder, the encoding ROS 2 records its messages in: for writing messages
//! of one's own, such as synthetic bags for tests and examples (with the `mcap` crate's writer).
//! Fields are appended in the order of the message definition; each is aligned to its size,
//! counted after the 4-byte encapsulation header, as ROS 2's serializer does.

/// A value CDR (or a ROS 2 message type) cannot hold.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum CdrWriteError {
    /// A string of this many bytes: CDR counts a string's bytes and its NUL in a `uint32`.
    #[error("a CDR string holds at most 4294967294 bytes, this one has {0}")]
    StringTooLong(usize),
    /// A stamp (ns since the epoch) whose seconds do not fit `builtin_interfaces/Time`'s `int32`.
    #[error("the stamp {0} ns is beyond 2038: builtin_interfaces/Time holds its seconds in an int32")]
    StampTooLate(u64),
}

/// One message being encoded. The methods append a field and return the writer, so that a
/// message reads as its definition: `w.header(t, "imu_link")?.f64(0.0)…`.
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
    /// # Errors
    /// [`CdrWriteError::StringTooLong`] beyond what a `uint32` length counts; nothing is written.
    pub fn string(&mut self, s: &str) -> Result<&mut Self, CdrWriteError> {
        let len = u32::try_from(s.len() + 1).map_err(|_| CdrWriteError::StringTooLong(s.len()))?;
        self.u32(len);
        self.buf.extend_from_slice(s.as_bytes());
        self.buf.push(0);
        Ok(self)
    }

    /// A `std_msgs/Header`: the stamp (`sec`, `nanosec`) of `stamp_ns` nanoseconds, and `frame_id`.
    ///
    /// # Errors
    /// [`CdrWriteError::StampTooLate`] for a stamp whose seconds exceed `int32` (after 2038), or a
    /// `frame_id` too long; nothing is written.
    pub fn header(&mut self, stamp_ns: u64, frame_id: &str) -> Result<&mut Self, CdrWriteError> {
        let sec = i32::try_from(stamp_ns / 1_000_000_000).map_err(|_| CdrWriteError::StampTooLate(stamp_ns))?;
        u32::try_from(frame_id.len() + 1).map_err(|_| CdrWriteError::StringTooLong(frame_id.len()))?;
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
        w.u8(7).f64(1.5).u16(3).string("ab").unwrap().header(2_000_000_003, "f").unwrap();
        let mut expected = vec![0, 1, 0, 0, 7, 0, 0, 0, 0, 0, 0, 0];
        expected.extend_from_slice(&1.5f64.to_le_bytes());
        expected.extend_from_slice(&[3, 0, 0, 0, 3, 0, 0, 0, b'a', b'b', 0, 0]);
        expected.extend_from_slice(&[2, 0, 0, 0, 3, 0, 0, 0, 2, 0, 0, 0, b'f', 0]);
        assert_eq!(w.bytes(), &expected[..]);
        assert_eq!(w.clear().bytes(), &[0, 1, 0, 0]);
        let late = w.header(u64::MAX, "f").unwrap_err();
        assert_eq!(late, CdrWriteError::StampTooLate(u64::MAX));
        assert!(late.to_string().contains("beyond 2038"), "{late}");
        assert_eq!(w.bytes(), &[0, 1, 0, 0], "a refused field writes nothing");
    }
}
