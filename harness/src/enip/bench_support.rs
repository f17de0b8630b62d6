//! What the EtherNet/IP speed bench (`harness/benches/enip/`, `cargo bench -p harness --bench
//! enip`) needs of the library, and nothing of the bench itself: the simulator served as an
//! adapter the way `harness serve enip` serves it, and the harness's own scanner (the binding
//! of `harness run --dut enip://…`) reading one parameter. The bench's rounds, clients, I/O
//! connection and figures are in the bench target; its statistics in [`crate::stats`].

use std::net::SocketAddr;
use std::time::Duration;

use proto::nord::{Inverter, ParamNumber, Product};
use sim::device::DeviceConfig;

use super::Scanner;
use crate::binding::Binding;
use crate::suite::{Action, OrderSpec, Target};

/// The addresses of an adapter [`serve`] put on the network.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ServedAdapter {
    /// Encapsulation messages, TCP and UDP.
    pub listen: SocketAddr,
    /// Class-1 I/O (UDP 2222 on the same IP).
    pub io: SocketAddr,
}

/// Serves a simulated device on `listen` (an IPv4 address; class-1 I/O on UDP 2222 of the
/// same IP) as `harness serve enip` does with its default limits, in threads of this process
/// that serve until it ends (the process's soft limit of open files raised to its hard
/// limit). An error says which socket could not be bound.
pub fn serve(listen: SocketAddr, config: DeviceConfig) -> Result<ServedAdapter, String> {
    let served = super::serve::start_enip(listen, config, Default::default(), Default::default())
        .map_err(|e| e.to_string())?;
    Ok(ServedAdapter {
        listen: served.listen,
        io: served.io,
    })
}

/// The harness scanner on a connection and session of its own, reading one NORD parameter
/// of one inverter (Get_Attribute_Single of its parameter class, BU 0620 §2.3.5) as a suite's
/// `read` step does, transcript included. Stays on the thread that made it; dropping it
/// unregisters its session.
pub struct ParamReader {
    scanner: Scanner,
    read: Action,
    /// `P102`, for messages.
    name: String,
}

impl ParamReader {
    /// Connects to the adapter at `target` (a `product`, for its parameter classes) to read
    /// parameter `number` of `inverter` (set 1, from the EEPROM's working copy as a `read`
    /// step does); `timeout` bounds each request.
    pub fn connect(
        target: SocketAddr,
        product: Product,
        inverter: Inverter,
        number: ParamNumber,
        timeout: Duration,
    ) -> Result<ParamReader, String> {
        let scanner =
            Scanner::network(target, None, Some(product), timeout).map_err(|e| e.to_string())?;
        Ok(ParamReader {
            scanner,
            read: Action::Read(OrderSpec::read(Target::Inverter(inverter), number)),
            name: format!("P{}", number.get()),
        })
    }

    /// One read, and the step's transcript taken as the runner takes it after each step. An
    /// error when it was not answered with CIP general status 0.
    pub fn read(&mut self) -> Result<(), String> {
        let v = self
            .scanner
            .perform(&self.read)
            .map_err(|e| format!("{e:?}"))?
            .fields;
        self.scanner.take_exchanges();
        match v.get("cip_status").and_then(serde_json::Value::as_u64) {
            Some(0) => Ok(()),
            _ => Err(format!("{} read refused: {v}", self.name)),
        }
    }
}

impl std::fmt::Debug for ParamReader {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ParamReader")
            .field("read", &self.name)
            .finish_non_exhaustive()
    }
}
