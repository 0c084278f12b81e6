//! A peer that never answers: what a vehicle that is off, or a wrong
//! port, looks like from the sending side.

/// A bound UDP socket that never answers, counting the PINGs it is sent
/// from what the kernel holds, without waiting.
pub struct SilentPeer {
    socket: std::net::UdpSocket,
    pings: u64,
}

impl SilentPeer {
    pub fn bind() -> Self {
        let socket = std::net::UdpSocket::bind("127.0.0.1:0").unwrap();
        socket.set_nonblocking(true).unwrap();
        SilentPeer { socket, pings: 0 }
    }

    pub fn port(&self) -> u16 {
        self.socket.local_addr().unwrap().port()
    }

    /// Every PING received so far (MAVLink message id 4).
    pub fn pings(&mut self) -> u64 {
        let mut buf = [0u8; 2048];
        while let Ok(n) = self.socket.recv(&mut buf) {
            let data = &buf[..n];
            let frames = super::frame_oracle::good_frames(data);
            for f in super::frame_oracle::isolated(&frames) {
                let b = &data[f];
                let msgid = match b[0] {
                    0xFD => u32::from_le_bytes([b[7], b[8], b[9], 0]),
                    _ => u32::from(b[5]),
                };
                self.pings += u64::from(msgid == 4);
            }
        }
        self.pings
    }
}
