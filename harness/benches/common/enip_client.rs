//! The benches' minimal EtherNet/IP client: encode, send, receive, decode and nothing else,
//! which shows what the simulator and loopback allow a client (the EtherNet/IP bench) and is
//! the soak's good client; and the Forward_Open of the EtherNet/IP bench's I/O connection.

use std::net::{SocketAddr, TcpStream};
use std::time::Duration;

use proto::enip::cip::{class, MrRequest, MrResponse, Service};
use proto::enip::cm::{kind, ForwardClose, ForwardOpen, ForwardOpenReply, NetParams, Transport};
use proto::enip::cpf::{Cpf, Item};
use proto::enip::encap::{
    frame_len, Command as EncapCommand, EncapRepr, RegisterSession, SendData,
};
use proto::enip::epath::EPath;

use harness::poll::{PollingStream, REPLY_POLL};

/// Originator vendor id and serial number of the client's Forward_Open.
const VENDOR: u16 = 0x4E48;
const ORIGINATOR_SERIAL: u32 = 0x4E48_4245;
/// Timeout multiplier of the I/O connection: ×64, so an O→T frame that a busy host sends a
/// few RPIs late does not end the measurement; the jitter measured is the T→O side.
const IO_MULTIPLIER: u8 = 4;

/// How long it waits for a reply at all.
const TIMEOUT: Duration = Duration::from_secs(2);

/// The bench's minimal explicit client: one session, unconnected requests.
pub(crate) struct Client {
    tcp: PollingStream,
    session: u32,
    buf: Vec<u8>,
}

/// An open I/O connection, as the Forward_Open reply gave it.
pub(crate) struct IoConnection {
    pub(crate) o_t_id: u32,
    pub(crate) t_o_id: u32,
    pub(crate) serial: u16,
}

impl Client {
    pub(crate) fn connect(target: SocketAddr) -> Result<Client, String> {
        let tcp = TcpStream::connect_timeout(&target, Duration::from_secs(2))
            .map_err(|e| format!("cannot connect to {target}: {e}"))?;
        tcp.set_nodelay(true).map_err(|e| e.to_string())?;
        let tcp = PollingStream::new(tcp, REPLY_POLL).map_err(|e| e.to_string())?;
        let mut c = Client {
            tcp,
            session: 0,
            buf: Vec::new(),
        };
        let reply = c.exchange(&EncapRepr {
            command: EncapCommand::REGISTER_SESSION.0,
            data: RegisterSession::V1.emit(),
            ..EncapRepr::default()
        })?;
        if reply.status != 0 || reply.session == 0 {
            return Err(format!(
                "RegisterSession refused: status {:#x}",
                reply.status
            ));
        }
        c.session = reply.session;
        Ok(c)
    }

    /// The local address of the client's TCP connection, where T→O data is sent.
    pub(crate) fn local_addr(&self) -> std::io::Result<SocketAddr> {
        self.tcp.get().local_addr()
    }

    /// One encapsulation message and its reply.
    fn exchange(&mut self, msg: &EncapRepr) -> Result<EncapRepr, String> {
        let bytes = msg.emit().map_err(|e| e.to_string())?;
        self.tcp
            .write_all(&bytes, TIMEOUT)
            .map_err(|e| format!("TCP send failed: {e}"))?;
        let mut chunk = [0u8; 4096];
        loop {
            if let Some(n) = frame_len(&self.buf).filter(|n| self.buf.len() >= *n) {
                let reply = EncapRepr::parse(&self.buf[..n]).map_err(|e| e.to_string());
                self.buf.drain(..n);
                return reply;
            }
            match self.tcp.read(&mut chunk, TIMEOUT) {
                Ok(0) => return Err("the simulator closed the TCP connection".into()),
                Ok(n) => self.buf.extend_from_slice(&chunk[..n]),
                Err(e) => return Err(format!("TCP receive failed: {e}")),
            }
        }
    }

    /// An unconnected request (SendRRData) and its message-router reply.
    fn request(&mut self, req: &MrRequest) -> Result<MrResponse, String> {
        let reply = self.exchange(&send_rr_data(req, self.session)?)?;
        if reply.status != 0 {
            return Err(format!("SendRRData status {:#x}", reply.status));
        }
        let sd = SendData::parse(&reply.data).map_err(|e| e.to_string())?;
        let Some(Item::UnconnectedData(payload)) = sd.cpf.items.get(1) else {
            return Err("SendRRData reply without unconnected data item".into());
        };
        let resp = MrResponse::parse(payload).map_err(|e| e.to_string())?;
        if resp.general != 0 {
            return Err(format!(
                "{} {} refused: general status {:#04x}",
                Service(req.service),
                req.path,
                resp.general
            ));
        }
        Ok(resp)
    }

    /// Get_Attribute_Single of `path`.
    pub(crate) fn get(&mut self, path: &EPath) -> Result<Vec<u8>, String> {
        self.request(&MrRequest {
            service: Service::GET_ATTRIBUTE_SINGLE.0,
            path: path.clone(),
            data: Vec::new(),
        })
        .map(|r| r.data)
    }

    /// Forward_Open of a class-1 cyclic point-to-point connection to assembly points `o_t`
    /// and `t_o` with connection sizes `o_t_size` and `t_o_size`, RPI `rpi_us` both ways.
    pub(crate) fn forward_open(
        &mut self,
        o_t: u16,
        t_o: u16,
        o_t_size: u16,
        t_o_size: u16,
        rpi_us: u32,
    ) -> Result<IoConnection, String> {
        let np = |size: u16| NetParams::fixed(size, kind::POINT_TO_POINT);
        let serial = 0x4245;
        let fo = ForwardOpen {
            large: false,
            priority_tick: 0x0A,
            timeout_ticks: 0x0E,
            o_t_id: 0,
            t_o_id: 0x4245_0001,
            serial,
            vendor: VENDOR,
            originator_serial: ORIGINATOR_SERIAL,
            timeout_multiplier: IO_MULTIPLIER,
            o_t_rpi: rpi_us,
            o_t: np(o_t_size),
            t_o_rpi: rpi_us,
            t_o: np(t_o_size),
            transport: Transport::CLASS1_CYCLIC,
            path: EPath::io_connection(o_t, t_o),
        };
        let resp = self.request(&MrRequest {
            service: Service::FORWARD_OPEN.0,
            path: EPath::object(class::CONNECTION_MANAGER, 1),
            data: fo.emit(),
        })?;
        let r = ForwardOpenReply::parse(&resp.data).map_err(|e| format!("Forward_Open: {e}"))?;
        Ok(IoConnection {
            o_t_id: r.o_t_id,
            t_o_id: r.t_o_id,
            serial,
        })
    }

    pub(crate) fn forward_close(&mut self, serial: u16) -> Result<(), String> {
        let fc = ForwardClose {
            priority_tick: 0x0A,
            timeout_ticks: 0x0E,
            serial,
            vendor: VENDOR,
            originator_serial: ORIGINATOR_SERIAL,
            path: EPath::object(class::ASSEMBLY, 1),
        };
        self.request(&MrRequest {
            service: Service::FORWARD_CLOSE.0,
            path: EPath::object(class::CONNECTION_MANAGER, 1),
            data: fc.emit(),
        })
        .map(|_| ())
    }
}

/// `req` as an unconnected request (SendRRData: a null address item and the request) in
/// `session`.
pub(crate) fn send_rr_data(req: &MrRequest, session: u32) -> Result<EncapRepr, String> {
    let data = SendData {
        interface: 0,
        timeout: 0,
        cpf: Cpf::new(vec![Item::Null, Item::UnconnectedData(req.emit())]),
    }
    .emit()
    .map_err(|e| e.to_string())?;
    Ok(EncapRepr {
        command: EncapCommand::SEND_RR_DATA.0,
        session,
        data,
        ..EncapRepr::default()
    })
}

impl Drop for Client {
    /// Leaves the simulator as found: the session unregistered.
    fn drop(&mut self) {
        let bye = EncapRepr {
            command: EncapCommand::UNREGISTER_SESSION.0,
            session: self.session,
            ..EncapRepr::default()
        };
        if let Ok(b) = bye.emit() {
            let _ = self.tcp.write_all(&b, TIMEOUT);
        }
    }
}
