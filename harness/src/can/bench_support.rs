//! What the system-bus speed bench (`harness/benches/can/`, `cargo bench -p harness --bench
//! can`) needs of the library: the harness's own SDO client (the one `harness run --dut
//! socketcand://…` drives) on a socketcand link, and nothing of the bench itself. It records no
//! transcript worth keeping while it measures.

use std::net::SocketAddr;
use std::time::{Duration, Instant};

use super::link::Socketcand;
use super::sdo::Client;
use crate::stats::Rate;

/// The object read: P102 set 1 of FI 3, at 2066h:01h of node 36 (expedited, 2 bytes).
pub const NODE: u8 = 36;
/// Its index.
pub const INDEX: u16 = 0x2066;
/// Its sub-index.
pub const SUB: u8 = 1;

/// Reads made before the timed ones.
const WARM_UP: u32 = 100;

/// `count` complete SDO reads of [`INDEX`]:[`SUB`] of [`NODE`] on the bus `channel` of the
/// socketcand server at `addr`: each one the upload request sent and the node's answer with the
/// value received, one after the other.
pub fn sdo_reads(addr: SocketAddr, channel: &str, count: u32) -> Result<Rate, String> {
    let limit = Duration::from_secs(2);
    let link = Socketcand::connect(addr, channel, limit).map_err(|e| e.to_string())?;
    let mut client = Client::new(link, limit);
    let read = |client: &mut Client<Socketcand>| {
        let r = client.upload(NODE, INDEX, SUB).map_err(|e| e.to_string());
        client.take_exchanges();
        r
    };
    for _ in 0..WARM_UP {
        read(&mut client)?;
    }
    let start = Instant::now();
    for _ in 0..count {
        let value = read(&mut client)?;
        if value.len() != 2 {
            return Err(format!("P102 came back as {} bytes", value.len()));
        }
    }
    Ok(Rate {
        count: u64::from(count),
        secs: start.elapsed().as_secs_f64(),
    })
}
