//! The log's bytes, read in chunks on tokio's blocking pool ([`Input`]),
//! cancel-safe across `recv`: the one part of the link that does I/O.

use std::io::{self, Read};

use tokio::task::JoinHandle;

/// Bytes read at a time.
pub(crate) const READ_CHUNK: usize = 256 * 1024;

pub(super) type Reader = Box<dyn Read + Send>;
type Reading = JoinHandle<(Reader, Vec<u8>, io::Result<usize>)>;

/// The log's bytes, read on the blocking pool.
pub(super) struct Input {
    /// Idle: the reader and its chunk. Taken while a read is under way.
    pub(super) idle: Option<(Reader, Vec<u8>)>,
    /// A read under way, kept across a cancelled `recv`.
    pub(super) reading: Option<Reading>,
    pub(super) eof: bool,
}

impl Input {
    /// Appends the next chunk to `buf` (nothing at the end of the input).
    /// Cancel-safe: a read under way is picked up by the next call.
    pub(super) async fn read_into(&mut self, buf: &mut Vec<u8>) -> io::Result<()> {
        if self.reading.is_none() {
            let (mut reader, mut chunk) = self.idle.take().expect("idle between reads");
            self.reading = Some(tokio::task::spawn_blocking(move || {
                chunk.resize(READ_CHUNK, 0);
                let read = loop {
                    match reader.read(&mut chunk) {
                        Err(e) if e.kind() == io::ErrorKind::Interrupted => {}
                        other => break other,
                    }
                };
                (reader, chunk, read)
            }));
        }
        let done = self.reading.as_mut().expect("a read under way").await;
        self.reading = None;
        let (reader, chunk, read) = done.map_err(io::Error::other)?;
        let read = read.inspect(|&n| buf.extend_from_slice(&chunk[..n]));
        self.idle = Some((reader, chunk));
        self.eof = matches!(read, Ok(0));
        read.map(|_| ())
    }
}
