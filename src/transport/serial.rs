//! Serial ports: telemetry radios, USB autopilots, and pseudo-terminals.
//!
//! A serial port is a byte stream like TCP, so it shares the reconnecting
//! [`super::stream::StreamLink`]; only opening the device differs.

use std::io;

use tokio_serial::{SerialPortBuilderExt, SerialStream};

use super::stream::Connect;
use super::LinkKind;

/// pymavlink's and MAVProxy's default when no baud rate is given.
pub(crate) const DEFAULT_BAUD: u32 = 115_200;

pub(crate) struct SerialConnector {
    path: String,
    baud: u32,
    name: String,
}

impl SerialConnector {
    pub(crate) fn new(path: &str, baud: u32) -> Self {
        SerialConnector {
            path: path.to_string(),
            baud,
            name: format!("serial:{path}:{baud}"),
        }
    }
}

impl Connect for SerialConnector {
    type Stream = SerialStream;
    const KIND: LinkKind = LinkKind::Serial;

    fn name(&self) -> &str {
        &self.name
    }

    fn eof_reason(&self) -> &'static str {
        "device hung up (unplugged, or the pty closed)"
    }

    // Linux answers a read of a pty whose other side closed, or of a USB
    // adapter pulled out, with EIO as often as with end of file.
    #[cfg(unix)]
    fn is_hangup(&self, e: &io::Error) -> bool {
        e.raw_os_error() == Some(nix::errno::Errno::EIO as i32)
    }

    async fn connect(&self) -> io::Result<SerialStream> {
        // The port is opened exclusively (TIOCEXCL), so a device another
        // program holds fails here as "busy" instead of sharing its bytes.
        tokio_serial::new(&self.path, self.baud)
            .open_native_async()
            .map_err(io::Error::from)
            .map_err(|e| not_a_terminal(&self.path, e))
    }
}

/// libc's "Not a typewriter" for a file that is no serial device (a
/// regular file, /dev/null), said in words a user can act on.
#[cfg(unix)]
fn not_a_terminal(path: &str, e: io::Error) -> io::Error {
    // serialport keeps only the errno's words, not its number.
    let enotty = nix::errno::Errno::ENOTTY;
    if e.raw_os_error() != Some(enotty as i32) && e.to_string() != enotty.desc() {
        return e;
    }
    io::Error::other(format!(
        "{path} is not a serial device (the system says it is not a terminal): name a serial \
         port (/dev/ttyUSB0, /dev/ttyACM0, /dev/serial/by-id/...) or a pty"
    ))
}

/// Windows names ports (COM3), not files: the system's own error says
/// enough.
#[cfg(not(unix))]
fn not_a_terminal(_path: &str, e: io::Error) -> io::Error {
    e
}
