//! The one non-blocking receive both ends of the UDP link use.

use std::io;
use std::net::{SocketAddr, UdpSocket};

/// The next datagram waiting on a non-blocking `socket`, into `buf`: its length and sender, or
/// `None` when nothing waits (an ICMP "connection refused" from a peer not yet listening counts
/// as nothing waiting).
pub(crate) fn recv_waiting(
    socket: &UdpSocket,
    buf: &mut [u8],
) -> io::Result<Option<(usize, SocketAddr)>> {
    match socket.recv_from(buf) {
        Ok(r) => Ok(Some(r)),
        Err(e)
            if matches!(
                e.kind(),
                io::ErrorKind::WouldBlock | io::ErrorKind::ConnectionRefused
            ) =>
        {
            Ok(None)
        }
        Err(e) => Err(e),
    }
}
