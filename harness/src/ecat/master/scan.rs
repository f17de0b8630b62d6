//! Bring-up of a segment (ETG.1000.4 §5.4, ETG.1000.6 §6.4; BU 0620 §2.2.1 "addressing … is
//! carried out automatically by the bus master according to the physical connection
//! sequence"): count the slaves, put them into Init with their FMMUs and SyncManagers cleared,
//! give each a configured station address by its position, read its identification registers
//! and its SII; then mailbox and Pre-Operational, process data and Safe-Operational,
//! Operational.

use proto::nord::nmt::EcState;

use super::engine::{EscInfo, Master, SlaveInfo};
use super::error::{LinkFailure, NoSlave, Result};
use super::segment::Segment;
use super::wire;
use proto::ecat::al::AlControl;
use proto::ecat::register::{
    AL_CONTROL, FMMU_BASE, FMMU_LEN, SM_BASE, SM_LEN, STATION_ADDRESS, STATION_ALIAS, TYPE,
};
use proto::ecat::Command;

/// Cycles of valid outputs the master sends in Safe-Operational before it asks for
/// Operational (ETG.1000.6 §6.4.1: the slave expects valid outputs on that transition).
const CYCLES_BEFORE_OP: u64 = 3;

impl<S: Segment> Master<S> {
    /// Counts the slaves on the segment: the working counter of a broadcast read of register
    /// 0000h (each slave adds 1). 0 is [`NoSlave::NoneCounted`].
    pub(crate) fn count_slaves(&mut self) -> Result<u16> {
        let r = self.one(wire::read(Command::BRD, 0, 0x0000, 2))?;
        if r.wkc == 0 {
            return Err(LinkFailure::NoSlave(NoSlave::NoneCounted).into());
        }
        self.port.set_slaves_seen();
        Ok(r.wkc)
    }

    /// Scans the segment: counts the slaves, resets them to Init (error acknowledged, FMMUs
    /// and SyncManagers cleared), assigns station addresses from
    /// [`super::MasterConfig::station_base`] up by position, reads their identification and
    /// their SII. Stops the process data; forgets what an earlier scan found.
    pub(crate) fn scan(&mut self) -> Result<&[SlaveInfo]> {
        self.stop_cycling();
        self.cyclic = Default::default();
        self.slaves.clear();
        let n = self.count_slaves()?;
        let init = AlControl::request(EcState::Init, true);
        self.broadcast(AL_CONTROL, init.emit().to_vec(), n)?;
        self.broadcast(FMMU_BASE, vec![0; 16 * FMMU_LEN], n)?;
        // Twice: an ESC takes SyncManager start/length/control only while the SyncManager is
        // disabled, and the first write disables it.
        self.broadcast(SM_BASE, vec![0; 8 * SM_LEN], n)?;
        self.broadcast(SM_BASE, vec![0; 8 * SM_LEN], n)?;
        for position in 0..n {
            let station = self.config.station_base.wrapping_add(position);
            let adp = 0u16.wrapping_sub(position);
            self.expect(
                wire::write(
                    Command::APWR,
                    adp,
                    STATION_ADDRESS,
                    station.to_le_bytes().to_vec(),
                ),
                1,
            )?;
            self.slaves.push(SlaveInfo {
                position,
                station,
                esc: EscInfo::default(),
                sii: Default::default(),
                sii_raw: Vec::new(),
                mailbox: None,
                process: None,
                counter: 0,
                received: None,
            });
        }
        for position in 0..n {
            let station = self.config.station_base.wrapping_add(position);
            let esc = self.read_esc_info(station)?;
            self.set_state(station, EcState::Init)?;
            let (raw, sii) = self.read_sii_image(station)?;
            if let Some(s) = self.slave_mut(station) {
                s.esc = esc;
                s.sii = sii;
                s.sii_raw = raw;
            }
        }
        Ok(&self.slaves)
    }

    /// A broadcast write that every one of `n` slaves must take.
    fn broadcast(&mut self, ado: u16, data: Vec<u8>, n: u16) -> Result<()> {
        self.expect(wire::write(Command::BWR, 0, ado, data), n)
            .map(drop)
    }

    /// Reads registers 0000h–0009h and the alias of `station`.
    pub(crate) fn read_esc_info(&mut self, station: u16) -> Result<EscInfo> {
        let b = self.read_register(station, TYPE, 10)?;
        let alias = self.read_u16(station, STATION_ALIAS)?;
        Ok(EscInfo {
            kind: b[0],
            revision: b[1],
            build: u16::from_le_bytes([b[2], b[3]]),
            fmmus: b[4],
            sync_managers: b[5],
            ram_kib: b[6],
            ports: b[7],
            features: u16::from_le_bytes([b[8], b[9]]),
            alias,
        })
    }

    /// Scans and brings every slave to `target`: mailbox and Pre-Operational (slaves with a
    /// mailbox), process data and Safe-Operational with the cycle running, Operational. A
    /// refusal on the way is the slave's [`super::Refusal::Al`]. Init and Bootstrap as targets
    /// only scan (Bootstrap is then requested).
    pub(crate) fn bring_up(&mut self, target: EcState) -> Result<()> {
        self.scan()?;
        let stations: Vec<u16> = self.slaves.iter().map(|s| s.station).collect();
        let rank = |s: EcState| match s {
            EcState::Init | EcState::Bootstrap => 0,
            EcState::PreOperational => 1,
            EcState::SafeOperational => 2,
            EcState::Operational => 3,
        };
        if target == EcState::Bootstrap {
            for &s in &stations {
                if self.slave(s).is_some_and(|x| x.has_mailbox()) {
                    self.configure_mailbox(s)?;
                }
                self.set_state(s, EcState::Bootstrap)?;
            }
            return Ok(());
        }
        if rank(target) >= 1 {
            for &s in &stations {
                if self.slave(s).is_some_and(|x| x.has_mailbox()) {
                    self.configure_mailbox(s)?;
                }
                self.set_state(s, EcState::PreOperational)?;
            }
        }
        if rank(target) >= 2 {
            for &s in &stations {
                self.configure_process_data(s)?;
            }
            self.start_cycling();
            for &s in &stations {
                self.set_state(s, EcState::SafeOperational)?;
            }
        }
        if rank(target) >= 3 {
            self.run_cycles(CYCLES_BEFORE_OP)?;
            for &s in &stations {
                self.set_state(s, EcState::Operational)?;
            }
        }
        Ok(())
    }
}
