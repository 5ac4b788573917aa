//! Writing a recording.

use std::collections::{BTreeMap, HashMap};
use std::fs::File;
use std::io::BufWriter;
use std::path::{Path, PathBuf};

use anyhow::Context as _;
use nauta_messages::{Message, TypeInfo, codec};

use crate::schema::Schema;
use crate::{MESSAGE_ENCODING, PROFILE, SCHEMA_ENCODING};

/// How a recording is written.
#[derive(Debug, Clone, Copy)]
pub struct WriterOptions {
    /// zstd level (1 fastest; 19 smallest).
    pub zstd_level: u32,
    /// A chunk is closed once it holds this many uncompressed bytes (and at
    /// every [`LogWriter::flush`]).
    pub chunk_bytes: u64,
}

impl Default for WriterOptions {
    /// zstd level 3 and 4 MiB chunks: measured by `nauta bench log`.
    fn default() -> Self {
        WriterOptions {
            zstd_level: 3,
            chunk_bytes: 4 << 20,
        }
    }
}

/// A channel of a recording being written.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct ChannelId(u16);

/// An MCAP recording being written.
pub struct LogWriter {
    inner: mcap::Writer<BufWriter<File>>,
    path: PathBuf,
    schemas: HashMap<&'static str, u16>,
    channels: HashMap<String, (ChannelId, &'static str)>,
    written: u64,
}

impl std::fmt::Debug for LogWriter {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("LogWriter")
            .field("path", &self.path)
            .field("channels", &self.channels.len())
            .field("written", &self.written)
            .finish()
    }
}

impl LogWriter {
    /// Creates (or truncates) `path`.
    pub fn create(path: &Path, options: WriterOptions) -> anyhow::Result<Self> {
        if let Some(dir) = path.parent()
            && !dir.as_os_str().is_empty()
        {
            std::fs::create_dir_all(dir)
                .with_context(|| format!("cannot create {}", dir.display()))?;
        }
        let file =
            File::create(path).with_context(|| format!("cannot create {}", path.display()))?;
        let inner = mcap::WriteOptions::new()
            .profile(PROFILE)
            .library(concat!("nauta-log ", env!("CARGO_PKG_VERSION")))
            .compression(Some(mcap::Compression::Zstd))
            .compression_level(options.zstd_level)
            .chunk_size(Some(options.chunk_bytes))
            // Chunks are assembled in memory and written whole, so a cut file
            // holds complete chunks followed by at most one partial record.
            .disable_seeking(true)
            .create(BufWriter::with_capacity(1 << 20, file))
            .with_context(|| format!("cannot start an MCAP file at {}", path.display()))?;
        Ok(LogWriter {
            inner,
            path: path.to_owned(),
            schemas: HashMap::new(),
            channels: HashMap::new(),
            written: 0,
        })
    }

    /// The channel for `topic` carrying `ty`, added on first use.
    pub fn channel(&mut self, topic: &str, ty: &TypeInfo) -> anyhow::Result<ChannelId> {
        if let Some((id, type_name)) = self.channels.get(topic) {
            anyhow::ensure!(
                *type_name == ty.type_name,
                "channel {topic} carries {type_name}, not {}",
                ty.type_name
            );
            return Ok(*id);
        }
        let schema_id = match self.schemas.get(ty.type_name) {
            Some(id) => *id,
            None => {
                let id = self
                    .inner
                    .add_schema(ty.type_name, SCHEMA_ENCODING, &Schema::of(ty).to_bytes())
                    .context("cannot add a schema")?;
                self.schemas.insert(ty.type_name, id);
                id
            }
        };
        let mut meta = BTreeMap::new();
        meta.insert("type".to_owned(), ty.type_name.to_owned());
        let id = ChannelId(
            self.inner
                .add_channel(schema_id, topic, MESSAGE_ENCODING, &meta)
                .context("cannot add a channel")?,
        );
        self.channels.insert(topic.to_owned(), (id, ty.type_name));
        Ok(id)
    }

    /// Writes one encoded message; its header is read from the first 32 bytes.
    pub fn write(
        &mut self,
        channel: ChannelId,
        log_time_ns: u64,
        data: &[u8],
    ) -> anyhow::Result<()> {
        let header = crate::header_of(data)
            .ok_or_else(|| anyhow::anyhow!("a message of {} bytes has no header", data.len()))?;
        self.inner
            .write_to_known_channel(
                &mcap::records::MessageHeader {
                    channel_id: channel.0,
                    // MCAP's field is 32 bits; the full seq is in the payload.
                    sequence: header.seq as u32,
                    log_time: log_time_ns,
                    publish_time: header.stamp_ns,
                },
                data,
            )
            .with_context(|| format!("cannot write to {}", self.path.display()))?;
        self.written += 1;
        Ok(())
    }

    /// Encodes and writes `msg` on `topic`.
    pub fn write_message<M: Message>(
        &mut self,
        topic: &str,
        log_time_ns: u64,
        msg: &M,
    ) -> anyhow::Result<()> {
        let ch = self.channel(topic, &TypeInfo::of::<M>())?;
        let bytes = codec::encode(msg)?;
        self.write(ch, log_time_ns, &bytes)
    }

    /// Writes a metadata record (in the data section, so it survives a cut).
    pub fn metadata(
        &mut self,
        name: &str,
        entries: BTreeMap<String, String>,
    ) -> anyhow::Result<()> {
        self.inner
            .write_metadata(&mcap::records::Metadata {
                name: name.to_owned(),
                metadata: entries,
            })
            .with_context(|| format!("cannot write metadata to {}", self.path.display()))
    }

    /// Closes the current chunk and hands everything to the operating system:
    /// what was written so far survives a crash of this process.
    pub fn flush(&mut self) -> anyhow::Result<()> {
        self.inner
            .flush()
            .with_context(|| format!("cannot flush {}", self.path.display()))
    }

    /// Messages written so far.
    pub fn written(&self) -> u64 {
        self.written
    }

    /// Writes the summary and footer and closes the file.
    pub fn finish(mut self) -> anyhow::Result<()> {
        self.inner
            .finish()
            .with_context(|| format!("cannot finish {}", self.path.display()))?;
        let mut buf = self.inner.into_inner();
        std::io::Write::flush(&mut buf)
            .with_context(|| format!("cannot flush {}", self.path.display()))?;
        buf.get_ref()
            .sync_all()
            .with_context(|| format!("cannot sync {}", self.path.display()))
    }
}
