//! Serial ports: telemetry radios, USB autopilots, and pseudo-terminals.
//!
//! A serial port is a byte stream like TCP, so it shares the reconnecting
//! [`super::stream::StreamLink`]; only opening the device differs.

use std::io;

use tokio_serial::{SerialPortBuilderExt, SerialStream};

use super::stream::Connect;
use super::LinkKind;

/// pymavlink's and MAVProxy's default when no baud rate is given.
pub const DEFAULT_BAUD: u32 = 115_200;

pub struct SerialConnector {
    path: String,
    baud: u32,
    name: String,
}

impl SerialConnector {
    pub fn new(path: &str, baud: u32) -> Self {
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

    async fn connect(&self) -> io::Result<SerialStream> {
        // The port is opened exclusively (TIOCEXCL), so a device another
        // program holds fails here as "busy" instead of sharing its bytes.
        tokio_serial::new(&self.path, self.baud)
            .open_native_async()
            .map_err(io::Error::from)
    }
}
