//! Slots, subslots and the pluggable modules of the two products (BU 0620 §2.5.5, §2.5.6.1,
//! §4.4.3; BU 0590 §4.2.1, §5.1.2 P163, §5.1.4 P180): the DAP in slot 0, the inverters' PPO
//! modules, the SK TU3-PNT's DIG-IO module, and what P879 / P180 display.

use serde::Serialize;

use super::{device_id, profinet, PnioError};
use crate::nord::ppo::PpoType;
use crate::nord::product::Product;
use crate::nord::types::Inverter;
use crate::pnio::plan::ExpectedSub;

/// Slot of the device access point.
pub const DAP_SLOT: u16 = 0;
/// Subslot of the DAP submodule.
pub const DAP_SUBSLOT: u16 = 1;
/// Subslot of the interface submodule (IEC 61158-6-10: 8000h + 100h·interface).
pub const INTERFACE_SUBSLOT: u16 = 0x8000;
/// Subslots of the two ports.
pub const PORT_SUBSLOTS: [u16; 2] = [0x8001, 0x8002];
/// Subslot of the one submodule of every I/O module.
pub const IO_SUBSLOT: u16 = 1;
/// DAP module ident number (assumed, see the module documentation).
pub const DAP_MODULE_IDENT: u32 = 0x0000_0001;
/// DAP submodule ident number (subslot 1).
pub const DAP_SUBMODULE_IDENT: u32 = 0x0000_0001;
/// Interface submodule ident number (subslot 8000h).
pub const INTERFACE_SUBMODULE_IDENT: u32 = 0x0000_8000;
/// Port submodule ident numbers (subslots 8001h, 8002h).
pub const PORT_SUBMODULE_IDENTS: [u32; 2] = [0x0000_8001, 0x0000_8002];

/// What a slot holds.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum SlotRole {
    /// The device access point (BU 0620 Fig. 15 "DAP"; BU 0590 P163 [-01] "Slot 0 (DAP)").
    Dap,
    /// A slot the manual reserves or does not name.
    Reserved,
    /// The SK TU3-PNT's own module ("Slot 2 (TU)", BU 0590 §4.2.1, P163 [-03]).
    BusModule,
    /// The module of FI n.
    Inverter(Inverter),
}

/// Number of slots (0..count): SK 550P DAP + FI 1..8 in slots 3..10 (BU 0620 §2.5.6.1 Fig. 16
/// "Slot 3...10", §2.5.6.2 "FI 1 (Slot 3)"); SK TU3-PNT slots 0..6 (BU 0590 P163 [-01]..[-07]).
pub fn slot_count(product: Product) -> u16 {
    match product {
        Product::Sk550p => 11,
        Product::Tu3Pnt => 7,
        _ => 0,
    }
}

/// What `slot` holds on `product`, `None` beyond its slots. BU 0620 names no use for slots 1
/// and 2 (Fig. 15 shows the DAP, then FI 1..8): reserved.
pub fn slot_role(product: Product, slot: u16) -> Option<SlotRole> {
    let fi = |n: u16| Inverter::new(i64::from(n)).ok().map(SlotRole::Inverter);
    match (product, slot) {
        (Product::Sk550p | Product::Tu3Pnt, 0) => Some(SlotRole::Dap),
        (Product::Sk550p, 1 | 2) => Some(SlotRole::Reserved),
        (Product::Sk550p, 3..=10) => fi(slot - 2),
        (Product::Tu3Pnt, 2) => Some(SlotRole::BusModule),
        (Product::Tu3Pnt, 3) => fi(1),
        (Product::Tu3Pnt, 1 | 4..=6) => Some(SlotRole::Reserved),
        _ => None,
    }
}

/// The slot of FI `inverter`: 2 + n on the SK 550P, 3 on the SK TU3-PNT.
pub fn inverter_slot(product: Product, inverter: Inverter) -> Result<u16, PnioError> {
    profinet(product)?;
    let n = inverter.get();
    if n > product.max_inverters() {
        return Err(PnioError::NoSuchInverter {
            product: product.name(),
            inverter: n,
            max: product.max_inverters(),
        });
    }
    Ok(2 + u16::from(n))
}

/// What a pluggable I/O module carries.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum ModuleKind {
    /// An inverter's PPO (BU 0620 §2.5.5.1, BU 0590 §4.1.1).
    Ppo(#[serde(serialize_with = "ppo_number")] PpoType),
    /// The SK TU3-PNT's "DIG-IO, process data for the TU" (BU 0590 P180 value 2).
    DigIo,
}

fn ppo_number<S: serde::Serializer>(t: &PpoType, s: S) -> Result<S::Ok, S::Error> {
    s.serialize_u8(t.0)
}

/// One pluggable module of the device description.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub struct Module {
    /// Module ident number (= the P879 / P180 display value, see the module documentation).
    pub ident: u32,
    /// Ident number of its one submodule (subslot 1): the same number.
    pub submodule_ident: u32,
    /// What it carries.
    pub kind: ModuleKind,
    /// Bytes from the controller (control word, setpoints; PKW order first for PPO 1/2).
    pub output_len: usize,
    /// Bytes to the controller (status word, actual values; PKW response first).
    pub input_len: usize,
}

impl Module {
    /// The module's name as the manuals write it ("PPO3", "DIG-IO").
    pub fn name(&self) -> String {
        match self.kind {
            ModuleKind::Ppo(t) => format!("PPO{}", t.0),
            ModuleKind::DigIo => "DIG-IO".to_string(),
        }
    }
}

/// P180 value of the DIG-IO module (BU 0590 §5.1.4).
pub const DIG_IO_IDENT: u32 = 2;

/// The module of `kind` on `product`, `None` where the product has none.
pub fn module(product: Product, kind: ModuleKind) -> Option<Module> {
    let (ident, len) = match kind {
        ModuleKind::Ppo(t) => (
            u32::from(t.display_code(product)?),
            PpoType::new(t.0).ok()?.byte_len(),
        ),
        ModuleKind::DigIo if product == Product::Tu3Pnt => (DIG_IO_IDENT, 2),
        ModuleKind::DigIo => return None,
    };
    device_id(product)?;
    Some(Module {
        ident,
        submodule_ident: ident,
        kind,
        output_len: len,
        input_len: len,
    })
}

/// Every pluggable module of `product`, in the order of the display values.
pub fn modules(product: Product) -> Vec<Module> {
    let mut all: Vec<Module> = std::iter::once(ModuleKind::DigIo)
        .chain(PpoType::ALL.into_iter().map(ModuleKind::Ppo))
        .filter_map(|k| module(product, k))
        .collect();
    all.sort_by_key(|m| m.ident);
    all
}

/// The module with ident number `ident`, `None` for an unknown one (a Connect expecting it is
/// answered with a module difference).
pub fn module_by_ident(product: Product, ident: u32) -> Option<Module> {
    modules(product).into_iter().find(|m| m.ident == ident)
}

/// Whether `kind` may be plugged into `slot`: PPO modules in the inverter slots, DIG-IO in the
/// SK TU3-PNT's slot 2.
pub fn fits(product: Product, slot: u16, kind: ModuleKind) -> bool {
    match (slot_role(product, slot), kind) {
        (Some(SlotRole::Inverter(_)), ModuleKind::Ppo(_)) => module(product, kind).is_some(),
        (Some(SlotRole::BusModule), ModuleKind::DigIo) => true,
        _ => false,
    }
}

/// The parameter and element showing the module of FI `inverter`'s slot: P879 [-n] on the SK
/// 550P (BU 0620 §4.4.3 "[-01] … [-08] FI 1 … FI 8"), P180 [-03] on the SK TU3-PNT (BU 0590
/// §5.1.4 "[-03] = Slot 3 (FI)"; its P163 numbers elements slot + 1, see pnio-facts.md).
pub fn ppo_display(product: Product, inverter: Inverter) -> Result<(u16, u8), PnioError> {
    inverter_slot(product, inverter)?;
    Ok(match product {
        Product::Tu3Pnt => (180, 3),
        _ => (879, inverter.get()),
    })
}

/// What the PPO-type parameter shows for a slot: the module's ident, or "empty slot" — 3 on
/// the SK 550P (P879), 0 on the SK TU3-PNT (P180).
pub fn slot_display(product: Product, plugged: Option<ModuleKind>) -> Option<u16> {
    match plugged {
        Some(kind) => module(product, kind).and_then(|m| u16::try_from(m.ident).ok()),
        None => match product {
            Product::Sk550p => Some(3),
            Product::Tu3Pnt => Some(0),
            _ => None,
        },
    }
}

/// The DAP's submodules as a controller expects them: the DAP (subslot 1), the interface
/// (8000h) and the two ports, none with IO data.
pub fn expected_dap() -> Vec<ExpectedSub> {
    let dap = |subslot, ident| ExpectedSub {
        slot: DAP_SLOT,
        module_ident: DAP_MODULE_IDENT,
        subslot,
        ident,
        input_len: 0,
        output_len: 0,
    };
    let mut subs = vec![
        dap(DAP_SUBSLOT, DAP_SUBMODULE_IDENT),
        dap(INTERFACE_SUBSLOT, INTERFACE_SUBMODULE_IDENT),
    ];
    subs.extend(
        PORT_SUBSLOTS
            .iter()
            .zip(PORT_SUBMODULE_IDENTS)
            .map(|(s, i)| dap(*s, i)),
    );
    subs
}

/// A module in `slot` as a controller expects it: its one submodule in subslot 1 with the
/// module's lengths.
pub fn expected_module(slot: u16, module: &Module) -> ExpectedSub {
    ExpectedSub {
        slot,
        module_ident: module.ident,
        subslot: IO_SUBSLOT,
        ident: module.submodule_ident,
        input_len: module.input_len as u16,
        output_len: module.output_len as u16,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rstest::rstest;

    fn fi(n: i64) -> Inverter {
        Inverter::new(n).unwrap()
    }

    #[rstest]
    // BU 0620 §2.5.6.2 p. 53: FI 1 in slot 3; Fig. 16 p. 52: slots 3…10.
    #[case(Product::Sk550p, 0, Some(SlotRole::Dap))]
    #[case(Product::Sk550p, 2, Some(SlotRole::Reserved))]
    #[case(Product::Sk550p, 3, Some(SlotRole::Inverter(fi(1))))]
    #[case(Product::Sk550p, 10, Some(SlotRole::Inverter(fi(8))))]
    #[case(Product::Sk550p, 11, None)]
    // BU 0590 §5.1.2 P163 p. 35: slot 0 DAP, 1 reserved, 2 TU, 3 FI, 4…6 reserved.
    #[case(Product::Tu3Pnt, 1, Some(SlotRole::Reserved))]
    #[case(Product::Tu3Pnt, 2, Some(SlotRole::BusModule))]
    #[case(Product::Tu3Pnt, 3, Some(SlotRole::Inverter(fi(1))))]
    #[case(Product::Tu3Pnt, 6, Some(SlotRole::Reserved))]
    #[case(Product::Tu3Pnt, 7, None)]
    fn slot_layout(#[case] p: Product, #[case] slot: u16, #[case] role: Option<SlotRole>) {
        assert_eq!(slot_role(p, slot), role);
        assert_eq!(slot_role(p, slot).is_some(), slot < slot_count(p));
    }

    #[test]
    fn inverter_slots() {
        assert_eq!(inverter_slot(Product::Sk550p, fi(5)), Ok(7));
        assert_eq!(inverter_slot(Product::Tu3Pnt, fi(1)), Ok(3));
        assert!(matches!(
            inverter_slot(Product::Tu3Pnt, fi(2)),
            Err(PnioError::NoSuchInverter { max: 1, .. })
        ));
        assert_eq!(
            inverter_slot(Product::Tu4Pol, fi(1)),
            Err(PnioError::NotProfinet("tu4-pol"))
        );
    }

    #[test]
    fn modules_per_ppo_type() {
        // BU 0620 §4.4.3 p. 88: P879 6 = PPO3, 7 = PPO4, 8 = PPO6, 9 = PPO1, 10 = PPO2.
        let sk: Vec<(u32, String, usize)> = modules(Product::Sk550p)
            .iter()
            .map(|m| (m.ident, m.name(), m.input_len))
            .collect();
        assert_eq!(
            sk,
            [
                (6, "PPO3".into(), 4),
                (7, "PPO4".into(), 8),
                (8, "PPO6".into(), 12),
                (9, "PPO1".into(), 12),
                (10, "PPO2".into(), 16)
            ]
        );
        // BU 0590 §5.1.4 p. 37: P180 2 = DIG-IO, 3 = PPO3 … 5 = PPO6, 6 = PPO1, 7 = PPO2.
        let tu: Vec<u32> = modules(Product::Tu3Pnt).iter().map(|m| m.ident).collect();
        assert_eq!(tu, [2, 3, 4, 5, 6, 7]);
        assert_eq!(
            module_by_ident(Product::Tu3Pnt, 7).map(|m| m.kind),
            Some(ModuleKind::Ppo(PpoType::TYPE_2))
        );
        assert_eq!(module_by_ident(Product::Sk550p, 2), None);
        assert_eq!(module_by_ident(Product::Sk550p, 3), None); // 3 is "empty slot"
        assert!(fits(Product::Tu3Pnt, 2, ModuleKind::DigIo));
        assert!(!fits(Product::Tu3Pnt, 3, ModuleKind::DigIo));
        assert!(fits(Product::Sk550p, 10, ModuleKind::Ppo(PpoType::TYPE_6)));
        assert!(!fits(Product::Sk550p, 2, ModuleKind::Ppo(PpoType::TYPE_6)));
        assert!(!fits(Product::Sk550p, 3, ModuleKind::Ppo(PpoType(5))));
    }

    #[test]
    fn ppo_displays() {
        assert_eq!(ppo_display(Product::Sk550p, fi(4)), Ok((879, 4)));
        assert_eq!(ppo_display(Product::Tu3Pnt, fi(1)), Ok((180, 3)));
        // P879 3 = empty slot; P180 0 = empty slot.
        assert_eq!(slot_display(Product::Sk550p, None), Some(3));
        assert_eq!(slot_display(Product::Tu3Pnt, None), Some(0));
        assert_eq!(
            slot_display(Product::Tu3Pnt, Some(ModuleKind::DigIo)),
            Some(2)
        );
        assert_eq!(
            slot_display(Product::Sk550p, Some(ModuleKind::Ppo(PpoType::TYPE_1))),
            Some(9)
        );
    }
}
