//! An open bag: the memory-mapped file and its channels.

use std::collections::BTreeMap;
use std::fs::File;
use std::path::{Path, PathBuf};

use memmap2::Mmap;

use crate::container::{self, ChannelRec, SchemaRec, Walker};
use crate::error::{Error, Result};

/// The largest chunk (compressed or uncompressed) read by default: 256 MiB. Writers make chunks
/// of about 1 MiB; a chunk is decompressed whole (its CRC checked before its records are used),
/// so this bounds the memory of reading.
pub const DEFAULT_MAX_CHUNK_BYTES: usize = 256 << 20;

/// An MCAP file opened for reading. The file is memory-mapped, not read into the heap; its
/// schemas and channels come from the summary section (or, without one, from a walk of the data
/// section). Do not modify the file while a `Bag` maps it.
#[derive(Debug)]
pub struct Bag {
    path: PathBuf,
    map: Mmap,
    max_chunk: usize,
    pub(crate) schemas: BTreeMap<u16, SchemaRec>,
    pub(crate) channels: BTreeMap<u16, ChannelRec>,
}

impl Bag {
    /// Opens and maps `path`, with chunks of at most [`DEFAULT_MAX_CHUNK_BYTES`].
    ///
    /// # Errors
    /// [`Error::Io`] if the file cannot be opened or mapped, [`Error::NotMcap`] without the MCAP
    /// magic bytes at its start.
    pub fn open(path: impl AsRef<Path>) -> Result<Self> {
        Self::open_with_limit(path, DEFAULT_MAX_CHUNK_BYTES)
    }

    /// [`Bag::open`] with another limit on a chunk's size (bytes); larger chunks are errors.
    ///
    /// # Errors
    /// As [`Bag::open`].
    pub fn open_with_limit(path: impl AsRef<Path>, max_chunk_bytes: usize) -> Result<Self> {
        let path = path.as_ref().to_owned();
        let io = |source| Error::Io { path: path.clone(), source };
        let file = File::open(&path).map_err(io)?;
        let len = file.metadata().map_err(io)?.len();
        if len < mcap::MAGIC.len() as u64 {
            return Err(Error::NotMcap { path });
        }
        // SAFETY: the map is read-only and private to this value; the file must not be truncated
        // or rewritten while it is mapped (documented on `Bag`), as with any memory-mapped reader
        // (the `mcap` crate's own examples map files the same way).
        #[allow(unsafe_code)]
        let map = unsafe { Mmap::map(&file) }.map_err(io)?;
        if !map.starts_with(mcap::MAGIC) {
            return Err(Error::NotMcap { path });
        }
        let (schemas, channels) = container::channels(&map, &path, max_chunk_bytes);
        Ok(Self { path, map, max_chunk: max_chunk_bytes, schemas, channels })
    }

    /// The file's path.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// The topics of the bag, sorted, each once.
    pub fn topics(&self) -> Vec<String> {
        let mut t: Vec<String> = self.channels.values().map(|c| c.topic.clone()).collect();
        t.sort();
        t.dedup();
        t
    }

    /// The records of the data section, in file order.
    pub(crate) fn walker(&self) -> Walker<'_> {
        Walker::data(&self.map, &self.path, self.max_chunk)
    }
}
