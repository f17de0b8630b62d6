//! The EtherNet/IP Electronic Data Sheet (EDS) of a product, built from `proto` alone.
//!
//! Identity, assemblies, the run/idle rule (P166), the listen-only connection point, the RPI
//! range and the parameter classes come from [`proto::nord::eip`]; the NORD parameters from
//! the catalogue [`proto::nord::params::CATALOGUE`] (looked up with
//! [`proto::nord::params::lookup`], as the simulator does). The simulator therefore accepts
//! what the sheet describes, and the sheet changes when `proto` does.
//!
//! The text follows the ODVA EDS layout: INI-like sections, `Key = value;` entries (possibly
//! spanning lines), `$` comments, quoted strings. It is deterministic (fixed dates) and plain
//! ASCII: the manuals' `§`, `…`, `→`, `µ` are transliterated and double quotes inside strings
//! become single quotes.

use std::fmt::Write as _;

use crate::dictionary::DescribeError;
use proto::enip::cip::class;
use proto::enip::epath::EPath;
use proto::nord::addr::cip_instance;
use proto::nord::eip::{
    self, Assembly, Direction, IdentityInfo, LISTEN_ONLY_MAX, LISTEN_ONLY_POINT, RPI_RANGE,
    RUN_IDLE_HEADER_LEN, SEQUENCE_COUNT_LEN,
};
use proto::nord::params::{self, Access, Owner, ParamDef, Width, CATALOGUE};
use proto::nord::{ArrayElement, Family, Inverter, ParamNumber, ParamSet, Product};

/// The fixed creation and modification date of every generated sheet (`MM-DD-YYYY`).
const DATE: &str = "11-23-2026";
/// The fixed creation and modification time.
const TIME: &str = "00:00:00";
/// Vendor home page.
const HOME_URL: &str = "https://www.nord.com";
/// Class-3 (explicit message) connections the adapter accepts at once (the simulator's
/// `MAX_EXPLICIT`; `proto` does not state it).
const MAX_MSG_CONNECTIONS: usize = 6;
/// Default RPI of the RPI parameter, µs.
const RPI_DEFAULT: u32 = 10_000;

/// CIP elementary data types (CIP Vol. 1, appendix C).
const INT: u8 = 0xC3;
const DINT: u8 = 0xC4;
const UINT: u8 = 0xC7;
const UDINT: u8 = 0xC8;

/// Parameter descriptor bits.
const DESC_SCALING: u16 = 0x0004;
const DESC_READ_ONLY: u16 = 0x0010;

/// Trigger & transport: class 1, cyclic trigger, and the application type.
const TRANSPORT_CLASS_1: u32 = 1 << 1;
const TRIGGER_CYCLIC: u32 = 1 << 16;
const APP_LISTEN_ONLY: u32 = 1 << 24;
const APP_EXCLUSIVE_OWNER: u32 = 1 << 26;

/// Connection parameters (EDS `ConnectionN` second field).
const O_T_FIXED: u32 = 1 << 0;
const O_T_VARIABLE: u32 = 1 << 1;
const T_O_FIXED: u32 = 1 << 2;
const T_O_VARIABLE: u32 = 1 << 3;
/// Real-time formats (bits 8–10 for O→T, 12–14 for T→O).
const FORMAT_MODELESS: u32 = 0;
const FORMAT_HEARTBEAT: u32 = 3;
const FORMAT_RUN_IDLE: u32 = 4;
const O_T_FORMAT_SHIFT: u32 = 8;
const T_O_FORMAT_SHIFT: u32 = 12;
const O_T_POINT_TO_POINT: u32 = 1 << 18;
const T_O_MULTICAST: u32 = 1 << 21;
const T_O_POINT_TO_POINT: u32 = 1 << 22;
const O_T_SCHEDULED: u32 = 1 << 26;
const T_O_SCHEDULED: u32 = 1 << 30;

/// The EDS of an EtherNet/IP product with `inverters` inverters (FI 1..=n) behind the
/// interface. `Err` for products without EtherNet/IP and for an inverter count outside
/// 1..=the product's maximum.
pub(crate) fn eds(product: Product, inverters: u8) -> Result<String, DescribeError> {
    let Some(id) = eip::identity(product) else {
        return Err(DescribeError::NoInterface {
            product,
            bus: "EtherNet/IP",
            format: "EDS",
        });
    };
    DescribeError::check_inverters(product, inverters)?;
    let assemblies = eip::assemblies(product);
    let mut params = Vec::new();
    params.push(rpi_param());
    for a in assemblies.iter().filter(|a| a.variable) {
        params.push(size_param(a, inverters));
    }
    let iface_class = interface_class(product);
    for def in catalogue(product, Owner::Interface) {
        params.push(nord_param(def, iface_class, None));
    }
    for n in 1..=inverters {
        let fi = Inverter::new(i64::from(n))
            .map_err(|e| DescribeError::Inconsistent(format!("FI {n}: {e}")))?;
        for def in catalogue(product, Owner::Inverter) {
            params.push(nord_param(def, eip::param_class(Some(fi)), Some(fi)));
        }
    }
    let connections = connections(product);

    let mut out = String::new();
    write_file(&mut out, product, &id);
    write_params(&mut out, &params);
    write_assemblies(&mut out, assemblies);
    write_connections(&mut out, &connections);
    write_capacity(&mut out, product, &connections);
    write_object(
        &mut out,
        "TCP/IP Interface Class",
        "TCP/IP Interface Object",
        class::TCP_IP,
    );
    write_object(
        &mut out,
        "Ethernet Link Class",
        "Ethernet Link Object",
        class::ETHERNET_LINK,
    );
    Ok(out)
}

/// Writes one line; writing to a `String` cannot fail.
macro_rules! put {
    ($out:expr) => {
        $out.push('\n')
    };
    ($out:expr, $($arg:tt)*) => {{
        let _ = writeln!($out, $($arg)*);
    }};
}

/// An entry field with its `$` comment, aligned as EDS editors write them.
fn field(out: &mut String, value: &str, comment: &str) {
    put!(out, "                {value:<23} $ {comment}");
}

/// A quoted EDS string: ASCII only, no double quotes inside.
fn quoted(text: &str) -> String {
    format!("\"{}\"", ascii(text))
}

/// Transliterates the manuals' non-ASCII characters; anything else becomes `?`.
fn ascii(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    let mut chars = text.chars().peekable();
    while let Some(c) = chars.next() {
        match c {
            '"' | '\u{201C}' | '\u{201D}' | '\u{201E}' | '\u{2018}' | '\u{2019}' => out.push('\''),
            '\\' => out.push('/'),
            '\u{2026}' => out.push_str("..."),
            '\u{2013}' | '\u{2014}' | '\u{2212}' => out.push('-'),
            '\u{00A7}' => {
                out.push_str("sec. ");
                while chars.peek().is_some_and(|c| c.is_whitespace()) {
                    chars.next();
                }
            }
            '\u{00B5}' | '\u{03BC}' => out.push('u'),
            '\u{2192}' => out.push_str("->"),
            '\u{2190}' => out.push_str("<-"),
            '\u{21D2}' => out.push_str("=>"),
            '\u{00D7}' => out.push('x'),
            '\u{00B0}' => out.push_str(" deg"),
            '\u{00E4}' => out.push_str("ae"),
            '\u{00F6}' => out.push_str("oe"),
            '\u{00FC}' => out.push_str("ue"),
            '\u{00C4}' => out.push_str("Ae"),
            '\u{00D6}' => out.push_str("Oe"),
            '\u{00DC}' => out.push_str("Ue"),
            '\u{00DF}' => out.push_str("ss"),
            c if c.is_ascii_control() => out.push(' '),
            c if c.is_ascii() => out.push(c),
            _ => out.push('?'),
        }
    }
    out
}

/// A path as EDS writes it: `"20 65 24 00 30 66"`.
fn hex_path(bytes: &[u8]) -> String {
    let parts: Vec<String> = bytes.iter().map(|b| format!("{b:02X}")).collect();
    format!("\"{}\"", parts.join(" "))
}

/// One `[Params]` entry.
struct Param {
    /// Link path (empty: none).
    path: Vec<u8>,
    descriptor: u16,
    data_type: u8,
    data_size: u8,
    name: String,
    units: &'static str,
    help: String,
    min: i64,
    max: i64,
    default: i64,
    /// Multiplier, divisor, base, offset.
    scaling: (u32, u32, u32, i32),
    decimals: u8,
}

fn type_name(t: u8) -> &'static str {
    match t {
        INT => "INT",
        DINT => "DINT",
        UINT => "UINT",
        UDINT => "UDINT",
        _ => "?",
    }
}

/// The RPI parameter every connection refers to (`Param1`).
fn rpi_param() -> Param {
    Param {
        path: Vec::new(),
        descriptor: 0,
        data_type: UDINT,
        data_size: 4,
        name: "RPI".into(),
        units: "us",
        help: format!(
            "Requested packet interval of the I/O connections, {} to {} us (the simulator's \
             range; the manuals state none)",
            RPI_RANGE.start(),
            RPI_RANGE.end()
        ),
        min: i64::from(*RPI_RANGE.start()),
        max: i64::from(*RPI_RANGE.end()),
        default: i64::from(RPI_DEFAULT),
        scaling: (1, 1, 1, 0),
        decimals: 0,
    }
}

/// Bytes of a variable assembly that carry `inverters` inverters (and the I/O word).
fn bytes_for(a: &Assembly, inverters: u8) -> u16 {
    let words = u16::from(a.io_word)
        + u16::from(a.inverters.min(inverters)) * eip::WORDS_PER_INVERTER as u16;
    (words * 2).min(a.len)
}

/// The data size of a variable assembly's connections.
fn size_param(a: &Assembly, inverters: u8) -> Param {
    let dir = match a.direction {
        Direction::Output => "O->T (consumed)",
        Direction::Input => "T->O (produced)",
    };
    Param {
        path: Vec::new(),
        descriptor: 0,
        data_type: UINT,
        data_size: 2,
        name: format!("Size of assembly {}", a.instance),
        units: "bytes",
        help: format!(
            "{dir} data bytes of assembly {} ({}). Variable: a connection may carry the full {} \
             bytes or fewer in whole words (even sizes from 2), truncated from the end. With {} \
             behind the interface, {} bytes carry all of their data.",
            a.instance,
            a.description,
            a.len,
            if inverters == 1 {
                "1 inverter".to_string()
            } else {
                format!("{inverters} inverters")
            },
            bytes_for(a, inverters)
        ),
        min: 2,
        max: i64::from(a.len),
        default: i64::from(a.len),
        scaling: (1, 1, 1, 0),
        decimals: 0,
    }
}

/// The class of the bus interface's own parameters: 100 for a module; the SK 550P's
/// interface is built into FI 1, so its P85x..P89x answer in FI 1's class 101 (BU 0620 §2.3.5
/// lists classes 101..108 only; the simulator routes them so).
fn interface_class(product: Product) -> u16 {
    match product.family() {
        Family::Module => eip::param_class(None),
        Family::Integrated => eip::param_class(Inverter::new(1).ok()),
    }
}

/// The parameters a unit of `product` has, by number, as [`params::lookup`] finds them.
fn catalogue(product: Product, owner: Owner) -> Vec<&'static ParamDef> {
    let mut numbers: Vec<u16> = CATALOGUE
        .iter()
        .filter(|d| d.owner == owner && d.applies_to(product))
        .map(|d| d.number)
        .collect();
    numbers.sort_unstable();
    numbers.dedup();
    numbers
        .into_iter()
        .filter_map(|n| ParamNumber::new(i64::from(n)).ok())
        .filter_map(|n| params::lookup(product, owner, n))
        .collect()
}

/// A NORD parameter at parameter set 1 / element [-01] of its class.
fn nord_param(def: &ParamDef, class: u16, fi: Option<Inverter>) -> Param {
    let set = if def.set_dependent {
        ParamSet::new(1).ok()
    } else {
        None
    };
    let element = def.array.and_then(|_| ArrayElement::new(1).ok());
    let instance = cip_instance(set, element);
    let path = EPath::attribute(class, u32::from(instance), def.number).emit();
    let (data_type, data_size) = match def.width {
        Width::Dword => (DINT, 4),
        // A 16-bit parameter reaching above 32767 is unsigned on the wire (the simulator reads
        // INT only where the minimum is negative).
        Width::Word if def.min >= 0 && def.max > i32::from(i16::MAX) => (UINT, 2),
        Width::Word => (INT, 2),
    };
    let mut descriptor = 0;
    if def.access == Access::ReadOnly {
        descriptor |= DESC_READ_ONLY;
    }
    // Decimal places apply to the scaled value: 200 with 2 decimals shows 2.00 when divided
    // by 100.
    let div = 10u32.pow(u32::from(def.decimals));
    if def.decimals > 0 {
        descriptor |= DESC_SCALING;
    }
    let mut help = def.source.trim_end_matches('.').to_string();
    help.push_str(&format!(
        ". CIP class {class}, attribute {}, instance {instance}",
        def.number
    ));
    match (def.set_dependent, def.array) {
        (false, None) => {}
        (true, None) => {
            help.push_str(" = parameter set 1 (set-dependent: instances 0..3 address sets 1..4)")
        }
        (false, Some(n)) => help.push_str(&format!(
            " = element [-01] (array [-01]..[-{n:02}]: instance = element - 1)"
        )),
        (true, Some(n)) => help.push_str(&format!(
            " = element [-01], parameter set 1 (array [-01]..[-{n:02}] in 4 sets: instance = \
             (element - 1) * 4 + set - 1)"
        )),
    }
    help.push('.');
    match def.access {
        Access::ReadOnly => help.push_str(" Read only."),
        Access::ResetOnly => help.push_str(" Only 0 may be written (reset)."),
        Access::ReadWrite => {}
    }
    let name = match fi {
        Some(fi) => format!("{fi} P{:03} {}", def.number, def.name),
        None => format!("P{:03} {}", def.number, def.name),
    };
    Param {
        path,
        descriptor,
        data_type,
        data_size,
        name,
        units: "",
        help,
        min: i64::from(def.min),
        max: i64::from(def.max),
        default: i64::from(params::element_default(def, 1)),
        scaling: (1, div, 1, 0),
        decimals: def.decimals,
    }
}

/// One `[Connection Manager]` entry.
struct Connection {
    /// Exclusive owner's O→T assembly; `None` for listen only.
    o_t: Option<&'static Assembly>,
    t_o: &'static Assembly,
    /// P166 the entry assumes.
    p166: i32,
    run_idle: bool,
    name: String,
    help: String,
}

impl Connection {
    fn trigger(&self) -> u32 {
        let app = if self.o_t.is_some() {
            APP_EXCLUSIVE_OWNER
        } else {
            APP_LISTEN_ONLY
        };
        app | TRIGGER_CYCLIC | TRANSPORT_CLASS_1
    }

    fn parameters(&self) -> u32 {
        let (o_t_sizes, o_t_format) = match self.o_t {
            Some(a) => (
                O_T_FIXED | if a.variable { O_T_VARIABLE } else { 0 },
                if self.run_idle {
                    FORMAT_RUN_IDLE
                } else {
                    FORMAT_MODELESS
                },
            ),
            None => (O_T_FIXED, FORMAT_HEARTBEAT),
        };
        let t_o_sizes = T_O_FIXED | if self.t_o.variable { T_O_VARIABLE } else { 0 };
        o_t_sizes
            | t_o_sizes
            | o_t_format << O_T_FORMAT_SHIFT
            | FORMAT_MODELESS << T_O_FORMAT_SHIFT
            | O_T_POINT_TO_POINT
            | T_O_MULTICAST
            | T_O_POINT_TO_POINT
            | O_T_SCHEDULED
            | T_O_SCHEDULED
    }

    fn o_t_point(&self) -> u16 {
        self.o_t.map_or(LISTEN_ONLY_POINT, |a| a.instance)
    }

    /// `20 04 24 01 2C <O→T> 2C <T→O>`.
    fn path(&self) -> Vec<u8> {
        EPath::io_connection(self.o_t_point(), self.t_o.instance).emit()
    }

    fn sizes(&self, product: Product) -> (u16, u16) {
        eip::connection_sizes(product, self.o_t_point(), self.t_o.instance, self.p166)
    }
}

/// The P166 factory setting of a product, and its other values (none without P166: the
/// SK 550P's O→T data always carries the header).
fn p166_values(product: Product) -> (i32, Vec<i32>) {
    let def = eip::transmission_format(product)
        .and_then(|n| params::lookup(product, Owner::Interface, n));
    match def {
        Some(d) => (
            d.default,
            (d.min..=d.max).filter(|v| *v != d.default).collect(),
        ),
        None => (0, Vec::new()),
    }
}

/// The exclusive-owner pairs (the n-th output with the n-th input assembly).
fn pairs(product: Product) -> Vec<(&'static Assembly, &'static Assembly)> {
    let all = eip::assemblies(product);
    let outputs = all.iter().filter(|a| a.direction == Direction::Output);
    let inputs = all.iter().filter(|a| a.direction == Direction::Input);
    outputs.zip(inputs).collect()
}

fn size_text(o_t: Option<&Assembly>, run_idle: bool, t_o: &Assembly, sizes: (u16, u16)) -> String {
    let o_t_text = match o_t {
        Some(a) => format!(
            "O->T {} bytes ({SEQUENCE_COUNT_LEN} sequence count{} + {} data)",
            sizes.0,
            if run_idle {
                format!(" + {RUN_IDLE_HEADER_LEN} run/idle header")
            } else {
                String::new()
            },
            a.len
        ),
        None => format!(
            "O->T {} bytes (heartbeat without data; the adapter also accepts {SEQUENCE_COUNT_LEN}, \
             the sequence count alone)",
            sizes.0
        ),
    };
    format!(
        "CIP network connection sizes as a scanner configures them: {o_t_text}, T->O {} bytes \
         ({SEQUENCE_COUNT_LEN} sequence count + {} data).",
        sizes.1, t_o.len
    )
}

fn truncation_text(o_t: Option<&Assembly>, t_o: &Assembly) -> String {
    let variable: Vec<String> = o_t
        .into_iter()
        .chain([t_o])
        .filter(|a| a.variable)
        .map(|a| a.instance.to_string())
        .collect();
    if variable.is_empty() {
        String::new()
    } else {
        format!(
            " {} variable: the data may be truncated from the end in whole words, the \
             network sizes shrink by as much.",
            if variable.len() == 1 {
                format!("Assembly {} is", variable[0])
            } else {
                format!("Assemblies {} are", variable.join(" and "))
            }
        )
    }
}

/// Exclusive owner per pair at the factory P166, per pair and other P166 value that changes
/// the O→T header, then listen only per input assembly of a pair.
fn connections(product: Product) -> Vec<Connection> {
    let (factory, others) = p166_values(product);
    let mut out = Vec::new();
    let owner = |o: &'static Assembly, t: &'static Assembly, p166: i32, variant: bool| {
        let run_idle = eip::o_t_run_idle(product, o.instance, p166);
        let mut c = Connection {
            o_t: Some(o),
            t_o: t,
            p166,
            run_idle,
            name: format!("Exclusive Owner {}/{}", o.instance, t.instance),
            help: String::new(),
        };
        let header = if run_idle {
            "O->T data with the 32-bit run/idle header"
        } else {
            "O->T data modeless (no run/idle header)"
        };
        if variant {
            c.name.push_str(&format!(" (P166 = {p166})"));
        }
        c.help = format!(
            "Outputs {} ({}), inputs {} ({}). P166 = {p166}{}: {header}. {}{}",
            o.instance,
            o.description,
            t.instance,
            t.description,
            if variant { "" } else { " (factory setting)" },
            size_text(Some(o), run_idle, t, c.sizes(product)),
            truncation_text(Some(o), t)
        );
        c
    };
    for (o, t) in pairs(product) {
        out.push(owner(o, t, factory, false));
    }
    for (o, t) in pairs(product) {
        let mut seen = vec![eip::o_t_run_idle(product, o.instance, factory)];
        for &v in &others {
            let run_idle = eip::o_t_run_idle(product, o.instance, v);
            if !seen.contains(&run_idle) {
                seen.push(run_idle);
                out.push(owner(o, t, v, true));
            }
        }
    }
    for (_, t) in pairs(product) {
        let mut c = Connection {
            o_t: None,
            t_o: t,
            p166: factory,
            run_idle: false,
            name: format!("Listen Only {}", t.instance),
            help: String::new(),
        };
        c.help = format!(
            "Inputs {} ({}) of an open exclusive-owner connection; O->T connection point {}, at \
             most {} listen-only connections. {}{}",
            t.instance,
            t.description,
            LISTEN_ONLY_POINT,
            LISTEN_ONLY_MAX,
            size_text(None, false, t, c.sizes(product)),
            truncation_text(None, t)
        );
        out.push(c);
    }
    out
}

fn write_file(out: &mut String, product: Product, id: &IdentityInfo) {
    put!(
        out,
        "$ Electronic Data Sheet of the {} ({}), generated by the NORD bus-interface test harness",
        ascii(id.name),
        product.manual()
    );
    put!(
        out,
        "$ from proto::nord::eip and the parameter catalogue. The manual names the file {}.",
        ascii(id.eds_file)
    );
    put!(out);
    put!(out, "[File]");
    put!(
        out,
        "        DescText = {};",
        quoted(&format!("EDS for the {} EtherNet/IP adapter", id.name))
    );
    put!(out, "        CreateDate = {DATE};");
    put!(out, "        CreateTime = {TIME};");
    put!(out, "        ModDate = {DATE};");
    put!(out, "        ModTime = {TIME};");
    put!(out, "        Revision = 1.0;");
    put!(out, "        HomeURL = {};", quoted(HOME_URL));
    put!(out);
    put!(out, "[Device]");
    put!(out, "        VendCode = {};", id.vendor);
    put!(out, "        VendName = {};", quoted(id.vendor_name));
    put!(out, "        ProdType = {};", id.device_type);
    let type_text = if id.device_type == 0x0C {
        "Communications Adapter"
    } else {
        "Generic Device"
    };
    put!(out, "        ProdTypeStr = {};", quoted(type_text));
    put!(out, "        ProdCode = {};", id.product_code);
    put!(out, "        MajRev = {};", id.revision.0);
    put!(out, "        MinRev = {};", id.revision.1);
    put!(out, "        ProdName = {};", quoted(id.name));
    put!(out, "        Catalog = {};", quoted(id.name));
    put!(out);
    put!(out, "[Device Classification]");
    put!(out, "        Class1 = EtherNetIP;");
    put!(out);
}

fn write_params(out: &mut String, params: &[Param]) {
    put!(out, "[Params]");
    for (i, p) in params.iter().enumerate() {
        put!(out, "        Param{} =", i + 1);
        field(out, "0,", "reserved, shall equal 0");
        if p.path.is_empty() {
            field(out, ",,", "link path size, link path");
        } else {
            field(
                out,
                &format!("{},{},", p.path.len(), hex_path(&p.path)),
                "link path size, link path",
            );
        }
        field(out, &format!("0x{:04X},", p.descriptor), "descriptor");
        field(
            out,
            &format!("0x{:02X},", p.data_type),
            &format!("data type: {}", type_name(p.data_type)),
        );
        field(out, &format!("{},", p.data_size), "data size in bytes");
        field(out, &format!("{},", quoted(&p.name)), "name");
        field(out, &format!("{},", quoted(p.units)), "units");
        field(out, &format!("{},", quoted(&p.help)), "help string");
        field(
            out,
            &format!("{},{},{},", p.min, p.max, p.default),
            "min, max, default data values",
        );
        let (mult, div, base, offset) = p.scaling;
        field(
            out,
            &format!("{mult},{div},{base},{offset},"),
            "mult, div, base, offset scaling",
        );
        field(out, ",,,,", "mult, div, base, offset links");
        field(out, &format!("{};", p.decimals), "decimal places");
    }
    put!(out);
}

fn write_assemblies(out: &mut String, assemblies: &[Assembly]) {
    put!(out, "[Assembly]");
    put!(out, "        Object_Name = \"Assembly Object\";");
    put!(
        out,
        "        Object_Class_Code = 0x{:02X};",
        class::ASSEMBLY
    );
    for a in assemblies {
        let (kind, dir) = match a.direction {
            Direction::Output => ("Output", "O->T, consumed"),
            Direction::Input => ("Input", "T->O, produced"),
        };
        put!(
            out,
            "        $ {} ({dir}): {}",
            a.instance,
            ascii(a.description)
        );
        if a.variable {
            put!(
                out,
                "        $ variable: whole words from 2 to {} bytes, truncated from the end",
                a.len
            );
        } else {
            put!(out, "        $ fixed: exactly {} bytes", a.len);
        }
        let path = EPath::object(class::ASSEMBLY, u32::from(a.instance)).emit();
        put!(
            out,
            "        Assem{} = {}, {}, {}, 0x0000, ,, {},;",
            a.instance,
            quoted(&format!("{kind} {}", a.instance)),
            hex_path(&path),
            a.len,
            u32::from(a.len) * 8
        );
    }
    put!(out);
}

/// What the connection parameters say, for the entry's comment.
fn describe_parameters(c: &Connection) -> String {
    let sizes = |fixed: bool, variable: bool| match (fixed, variable) {
        (true, true) => "fixed/variable",
        (false, true) => "variable",
        _ => "fixed",
    };
    let o_t = match c.o_t {
        None => "heartbeat".to_string(),
        Some(a) => format!(
            "{}, {}",
            sizes(true, a.variable),
            if c.run_idle {
                "32-bit run/idle header"
            } else {
                "modeless"
            }
        ),
    };
    format!(
        "O->T {o_t}, point-to-point; T->O {}, modeless, multicast or point-to-point; scheduled",
        sizes(true, c.t_o.variable)
    )
}

fn write_connections(out: &mut String, connections: &[Connection]) {
    put!(out, "[Connection Manager]");
    put!(out, "        Object_Name = \"Connection Manager Object\";");
    put!(
        out,
        "        Object_Class_Code = 0x{:02X};",
        class::CONNECTION_MANAGER
    );
    for (i, c) in connections.iter().enumerate() {
        let app = if c.o_t.is_some() {
            "exclusive owner"
        } else {
            "listen only"
        };
        put!(out, "        Connection{} =", i + 1);
        field(
            out,
            &format!("0x{:08X},", c.trigger()),
            &format!("trigger & transport: class 1, cyclic, {app}"),
        );
        field(
            out,
            &format!("0x{:08X},", c.parameters()),
            &describe_parameters(c),
        );
        match c.o_t {
            Some(a) => field(
                out,
                &format!("Param1,{},Assem{},", a.len, a.instance),
                "O->T RPI, size, format",
            ),
            None => field(out, "Param1,0,,", "O->T RPI, size, format"),
        }
        field(
            out,
            &format!("Param1,{},Assem{},", c.t_o.len, c.t_o.instance),
            "T->O RPI, size, format",
        );
        field(out, ",,", "config part 1 size, format");
        field(out, ",,", "config part 2 size, format");
        field(out, &format!("{},", quoted(&c.name)), "connection name");
        field(out, &format!("{},", quoted(&c.help)), "help string");
        field(out, &format!("{};", hex_path(&c.path())), "path");
    }
    put!(out);
}

fn write_capacity(out: &mut String, product: Product, connections: &[Connection]) {
    put!(out, "[Capacity]");
    put!(
        out,
        "        MaxIOConnections = {};       $ 1 exclusive owner + {LISTEN_ONLY_MAX} listen only",
        1 + LISTEN_ONLY_MAX
    );
    put!(out, "        MaxMsgConnections = {MAX_MSG_CONNECTIONS};");
    let pps = 1_000_000 / RPI_RANGE.start();
    let mut specs: Vec<(&str, u16)> = Vec::new();
    for c in connections.iter().filter(|c| c.o_t.is_some()) {
        let (o_t, t_o) = c.sizes(product);
        for spec in [("Rx", o_t), ("Tx", t_o)] {
            if !specs.contains(&spec) {
                specs.push(spec);
            }
        }
    }
    for (i, (dir, size)) in specs.iter().enumerate() {
        put!(
            out,
            "        TSpec{} = {dir}, {size}, {pps};    $ direction, network size, packets/s",
            i + 1
        );
    }
    put!(out);
}

fn write_object(out: &mut String, section: &str, name: &str, code: u16) {
    put!(out, "[{section}]");
    put!(out, "        Object_Name = {};", quoted(name));
    put!(out, "        Object_Class_Code = 0x{code:02X};");
    put!(out, "        MaxInst = 1;");
    put!(out, "        Number_Of_Static_Instances = 1;");
    put!(out, "        Max_Number_Of_Dynamic_Instances = 0;");
    put!(out);
}

#[cfg(test)]
mod tests {
    use super::*;
    use rstest::rstest;

    const EIP: [Product; 4] = [
        Product::Sk550p,
        Product::Tu3Eip,
        Product::Tu4Eip,
        Product::Cu4Eip,
    ];

    type Section = (String, Vec<(String, String)>);

    /// A small EDS reader: `[Section]`, `Key = value;` (values may span lines and contain
    /// `;` and `$` inside quotes), `$` comments to the end of the line.
    fn parse(text: &str) -> Result<Vec<Section>, String> {
        let mut clean = String::new();
        let (mut quote, mut comment) = (false, false);
        for c in text.chars() {
            match c {
                '\n' => {
                    if quote {
                        return Err("newline inside a string".into());
                    }
                    comment = false;
                    clean.push(c);
                }
                _ if comment => {}
                '$' if !quote => comment = true,
                '"' => {
                    quote = !quote;
                    clean.push(c);
                }
                _ => clean.push(c),
            }
        }
        let mut sections: Vec<Section> = Vec::new();
        let mut rest = clean.as_str();
        loop {
            rest = rest.trim_start();
            if rest.is_empty() {
                return Ok(sections);
            }
            if let Some(r) = rest.strip_prefix('[') {
                let end = r.find(']').ok_or("unterminated section")?;
                sections.push((r[..end].to_string(), Vec::new()));
                rest = &r[end + 1..];
                continue;
            }
            let eq = rest
                .find('=')
                .ok_or_else(|| format!("no '=' in {rest:.40}"))?;
            let key = rest[..eq].trim().to_string();
            if key.is_empty() || key.contains(['"', ';', '[', ']', '\n']) {
                return Err(format!("bad key {key:?}"));
            }
            let value = &rest[eq + 1..];
            let mut quote = false;
            let end = value
                .char_indices()
                .find(|&(_, c)| {
                    if c == '"' {
                        quote = !quote;
                    }
                    c == ';' && !quote
                })
                .map(|(i, _)| i)
                .ok_or_else(|| format!("{key}: no ';'"))?;
            let entries = &mut sections
                .last_mut()
                .ok_or_else(|| format!("{key} outside a section"))?
                .1;
            entries.push((key, value[..end].trim().to_string()));
            rest = &value[end + 1..];
        }
    }

    /// The comma-separated fields of a value (commas inside quotes do not split).
    fn fields(value: &str) -> Vec<String> {
        let mut out = vec![String::new()];
        let mut quote = false;
        for c in value.chars() {
            match c {
                '"' => {
                    quote = !quote;
                    out.last_mut().unwrap().push(c);
                }
                ',' if !quote => out.push(String::new()),
                _ => out.last_mut().unwrap().push(c),
            }
        }
        out.into_iter().map(|f| f.trim().to_string()).collect()
    }

    fn unquote(f: &str) -> &str {
        f.strip_prefix('"')
            .and_then(|f| f.strip_suffix('"'))
            .unwrap_or_else(|| panic!("not a string: {f}"))
    }

    fn hex(f: &str) -> Vec<u8> {
        unquote(f)
            .split_whitespace()
            .map(|b| u8::from_str_radix(b, 16).unwrap())
            .collect()
    }

    fn section<'a>(ini: &'a [Section], name: &str) -> &'a [(String, String)] {
        &ini.iter()
            .find(|(n, _)| n == name)
            .unwrap_or_else(|| panic!("no [{name}]"))
            .1
    }

    fn get<'a>(entries: &'a [(String, String)], key: &str) -> &'a str {
        entries
            .iter()
            .find(|(k, _)| k == key)
            .map(|(_, v)| v.as_str())
            .unwrap_or_else(|| panic!("no {key}"))
    }

    fn sheet(p: Product) -> Vec<Section> {
        let text = eds(p, p.max_inverters()).unwrap();
        parse(&text).unwrap_or_else(|e| panic!("{p:?}: {e}\n{text}"))
    }

    /// Param fields by entry number.
    fn params_of(ini: &[Section]) -> Vec<(String, Vec<String>)> {
        section(ini, "Params")
            .iter()
            .map(|(k, v)| (k.clone(), fields(v)))
            .collect()
    }

    #[rstest]
    fn every_eip_product_has_the_sections_and_keys(
        #[values(Product::Sk550p, Product::Tu3Eip, Product::Tu4Eip, Product::Cu4Eip)] p: Product,
    ) {
        let ini = sheet(p);
        let file = section(&ini, "File");
        for key in [
            "DescText",
            "CreateDate",
            "CreateTime",
            "ModDate",
            "ModTime",
            "Revision",
            "HomeURL",
        ] {
            get(file, key);
        }
        assert_eq!(get(file, "Revision"), "1.0");
        let dev = section(&ini, "Device");
        for key in [
            "VendName",
            "ProdType",
            "ProdTypeStr",
            "MajRev",
            "MinRev",
            "ProdName",
            "Catalog",
        ] {
            get(dev, key);
        }
        let id = eip::identity(p).unwrap();
        assert_eq!(get(dev, "VendCode"), id.vendor.to_string());
        assert_eq!(get(dev, "ProdCode"), id.product_code.to_string());
        assert_eq!(get(dev, "ProdType"), id.device_type.to_string());
        assert_eq!(get(dev, "MajRev"), id.revision.0.to_string());
        assert_eq!(get(dev, "MinRev"), id.revision.1.to_string());
        assert_eq!(unquote(get(dev, "ProdName")), id.name);
        assert_eq!(
            get(section(&ini, "Device Classification"), "Class1"),
            "EtherNetIP"
        );
        assert_eq!(
            get(section(&ini, "Connection Manager"), "Object_Class_Code"),
            "0x06"
        );
        assert_eq!(get(section(&ini, "Assembly"), "Object_Class_Code"), "0x04");
        assert_eq!(
            get(section(&ini, "TCP/IP Interface Class"), "Object_Class_Code"),
            "0xF5"
        );
        assert_eq!(
            get(section(&ini, "Ethernet Link Class"), "Object_Class_Code"),
            "0xF6"
        );
        let cap = section(&ini, "Capacity");
        assert_eq!(
            get(cap, "MaxIOConnections"),
            (1 + LISTEN_ONLY_MAX).to_string()
        );
        assert_eq!(get(cap, "MaxMsgConnections"), "6");
        assert!(get(cap, "TSpec1").starts_with("Rx,"));
    }

    #[rstest]
    fn assemblies_have_their_length_and_path(
        #[values(Product::Sk550p, Product::Tu3Eip, Product::Tu4Eip, Product::Cu4Eip)] p: Product,
    ) {
        let ini = sheet(p);
        let asm: Vec<_> = section(&ini, "Assembly")
            .iter()
            .filter(|(k, _)| k.starts_with("Assem"))
            .collect();
        assert_eq!(asm.len(), eip::assemblies(p).len());
        for a in eip::assemblies(p) {
            let f = fields(get(
                section(&ini, "Assembly"),
                &format!("Assem{}", a.instance),
            ));
            assert_eq!(f.len(), 8, "{f:?}");
            assert_eq!(f[2], a.len.to_string());
            let path = EPath::parse(&hex(&f[1])).unwrap();
            assert_eq!(path.class_id(), Some(class::ASSEMBLY));
            assert_eq!(path.instance_id(), Some(u32::from(a.instance)));
        }
    }

    #[rstest]
    fn connections_name_assemblies_of_the_product(
        #[values(Product::Sk550p, Product::Tu3Eip, Product::Tu4Eip, Product::Cu4Eip)] p: Product,
    ) {
        let ini = sheet(p);
        let params = params_of(&ini);
        let cm = section(&ini, "Connection Manager");
        let conns: Vec<_> = cm
            .iter()
            .filter(|(k, _)| k.starts_with("Connection"))
            .collect();
        let (mut owners, mut listeners) = (0, 0);
        for (i, (key, value)) in conns.iter().enumerate() {
            assert_eq!(*key, format!("Connection{}", i + 1));
            let f = fields(value);
            assert_eq!(f.len(), 15, "{key}: {f:?}");
            let trigger = u32::from_str_radix(f[0].trim_start_matches("0x"), 16).unwrap();
            let path = EPath::parse(&hex(&f[14])).unwrap();
            assert_eq!(path.class_id(), Some(class::ASSEMBLY));
            let [o_t, t_o] = path.connection_points()[..] else {
                panic!("{key}: {path}");
            };
            let input = eip::assembly(p, t_o).unwrap();
            assert_eq!(input.direction, Direction::Input);
            assert_eq!(f[6], input.len.to_string());
            assert_eq!(f[7], format!("Assem{t_o}"));
            for rpi in [&f[2], &f[5]] {
                let n: usize = rpi.trim_start_matches("Param").parse().unwrap();
                assert_eq!(unquote(&params[n - 1].1[6]), "RPI");
            }
            let help = unquote(&f[13]);
            if o_t == LISTEN_ONLY_POINT {
                listeners += 1;
                assert_eq!(trigger, 0x0101_0002, "{key}");
                assert_eq!(f[3], "0");
                assert!(
                    help.contains(&format!(
                        "T->O {} bytes",
                        eip::connection_size(input.len, false)
                    )),
                    "{help}"
                );
            } else {
                owners += 1;
                assert_eq!(trigger, 0x0401_0002, "{key}");
                let output = eip::assembly(p, o_t).unwrap();
                assert_eq!(output.direction, Direction::Output);
                assert_eq!(f[3], output.len.to_string());
                assert_eq!(f[4], format!("Assem{o_t}"));
                let params = u32::from_str_radix(f[1].trim_start_matches("0x"), 16).unwrap();
                let run_idle = (params >> 8) & 7 == 4;
                let p166 = if run_idle { 0 } else { 1 };
                assert_eq!(eip::o_t_run_idle(p, o_t, p166), run_idle);
                let (n_o_t, n_t_o) = eip::connection_sizes(p, o_t, t_o, p166);
                assert!(help.contains(&format!("O->T {n_o_t} bytes")), "{help}");
                assert!(help.contains(&format!("T->O {n_t_o} bytes")), "{help}");
            }
        }
        assert_eq!(listeners, pairs(p).len());
        assert!(owners >= pairs(p).len());
        // The first connection is the first pair's exclusive owner at the factory P166.
        let first = fields(get(cm, "Connection1"));
        assert_eq!(hex(&first[14])[..4], [0x20, 0x04, 0x24, 0x01]);
    }

    #[test]
    fn sk550p_paths_and_header() {
        let ini = sheet(Product::Sk550p);
        let cm = section(&ini, "Connection Manager");
        let eo = fields(get(cm, "Connection1"));
        assert_eq!(unquote(&eo[14]), "20 04 24 01 2C 64 2C 65");
        assert_eq!(eo[1], "0x4464040F");
        let lo = fields(get(cm, "Connection2"));
        assert_eq!(unquote(&lo[14]), "20 04 24 01 2C FF 2C 65");
        assert_eq!(lo[0], "0x01010002");
        assert!(cm.iter().all(|(k, _)| k != "Connection3"));
    }

    #[test]
    fn tu4_has_a_modeless_variant_for_110() {
        let ini = sheet(Product::Tu4Eip);
        let cm = section(&ini, "Connection Manager");
        let names: Vec<String> = cm
            .iter()
            .filter(|(k, _)| k.starts_with("Connection"))
            .map(|(_, v)| unquote(&fields(v)[12]).to_string())
            .collect();
        assert_eq!(
            names,
            [
                "Exclusive Owner 100/101",
                "Exclusive Owner 110/111",
                "Exclusive Owner 110/111 (P166 = 1)",
                "Listen Only 101",
                "Listen Only 111",
            ]
        );
        let modeless = fields(get(cm, "Connection3"));
        assert!(unquote(&modeless[13]).contains("O->T 52 bytes"));
        assert_eq!(
            (u32::from_str_radix(modeless[1].trim_start_matches("0x"), 16).unwrap() >> 8) & 7,
            0
        );
    }

    #[rstest]
    fn params_are_well_formed(
        #[values(Product::Sk550p, Product::Tu3Eip, Product::Tu4Eip, Product::Cu4Eip)] p: Product,
    ) {
        let ini = sheet(p);
        let mut paths = Vec::new();
        for (i, (key, f)) in params_of(&ini).iter().enumerate() {
            assert_eq!(*key, format!("Param{}", i + 1));
            assert_eq!(f.len(), 21, "{key}: {f:?}");
            assert_eq!(f[0], "0");
            let size: u8 = f[5].parse().unwrap();
            let want = match f[4].as_str() {
                "0xC3" | "0xC7" => 2,
                "0xC4" | "0xC8" => 4,
                t => panic!("{key}: type {t}"),
            };
            assert_eq!(size, want, "{key}");
            let [min, max, default]: [i64; 3] = [&f[9], &f[10], &f[11]].map(|v| v.parse().unwrap());
            assert!(min <= default && default <= max, "{key}: {f:?}");
            if !f[2].is_empty() {
                let bytes = hex(&f[2]);
                assert_eq!(f[1], bytes.len().to_string(), "{key}");
                let path = EPath::parse(&bytes).unwrap();
                assert_eq!(path.emit(), bytes);
                assert!(!paths.contains(&bytes), "{key}: path twice");
                paths.push(bytes);
            }
        }
        // Every parameter the catalogue gives the interface and FI 1..n is in the sheet.
        let iface = catalogue(p, Owner::Interface).len();
        let fi = catalogue(p, Owner::Inverter).len();
        assert_eq!(paths.len(), iface + fi * usize::from(p.max_inverters()));
        assert!(iface > 0 && fi > 0);
    }

    #[test]
    fn p102_of_fi1_has_its_cip_path() {
        for p in EIP {
            let ini = sheet(p);
            let params = params_of(&ini);
            let (_, f) = params
                .iter()
                .find(|(_, f)| unquote(&f[6]).starts_with("FI 1 P102 "))
                .unwrap();
            assert_eq!(unquote(&f[2]), "20 65 24 00 30 66");
            assert_eq!(f[1], "6");
            assert_eq!(f[4], "0xC3");
            // 2.00 s: raw 200, divided by 100, 2 decimals.
            assert_eq!(
                &f[9..21],
                ["0", "32000", "200", "1", "100", "1", "0", "", "", "", "", "2"]
            );
            assert_eq!(f[3], "0x0004");
        }
    }

    #[test]
    fn interface_parameters_use_the_interface_class() {
        let find = |p: Product, name: &str| {
            let ini = sheet(p);
            params_of(&ini)
                .into_iter()
                .find(|(_, f)| unquote(&f[6]).starts_with(name))
                .map(|(_, f)| f)
                .unwrap_or_else(|| panic!("{p:?}: no {name}"))
        };
        // A module's own parameters: class 100.
        let p166 = find(Product::Tu4Eip, "P166 ");
        assert_eq!(unquote(&p166[2]), "20 64 24 00 30 A6");
        // The SK 550P's interface sits in FI 1: class 101, 16-bit attribute 850 = 0352h.
        let p850 = find(Product::Sk550p, "P850 ");
        assert_eq!(unquote(&p850[2]), "20 65 24 00 31 00 52 03");
        assert_eq!(p850[1], "8");
        assert_eq!(p850[11], "192");
        // Read-only display parameters.
        let p872 = find(Product::Sk550p, "P872 ");
        assert_eq!(p872[3], "0x0010");
        assert_eq!(p872[4], "0xC7");
        // FI 8 reaches class 108 on the TU3-EIP; the TU4-EIP stops at FI 4.
        assert_eq!(
            unquote(&find(Product::Tu3Eip, "FI 8 P102 ")[2]),
            "20 6C 24 00 30 66"
        );
        let tu4 = eds(Product::Tu4Eip, 4).unwrap();
        assert!(tu4.contains("\"FI 4 P102 ") && !tu4.contains("\"FI 5 "));
    }

    #[test]
    fn fewer_inverters_fewer_parameters() {
        let one = parse(&eds(Product::Tu3Eip, 1).unwrap()).unwrap();
        let names: Vec<String> = params_of(&one)
            .iter()
            .map(|(_, f)| unquote(&f[6]).to_string())
            .collect();
        assert!(names.iter().any(|n| n.starts_with("FI 1 ")));
        assert!(!names.iter().any(|n| n.starts_with("FI 2 ")));
    }

    #[rstest]
    #[case(Product::Tu3Pnt)]
    #[case(Product::Tu3Pol)]
    #[case(Product::Tu4Pol)]
    #[case(Product::Cu4Pol)]
    fn products_without_ethernet_ip_have_no_eds(#[case] p: Product) {
        let e = eds(p, 1).unwrap_err();
        assert!(
            matches!(e, DescribeError::NoInterface { product, format: "EDS", .. } if product == p),
            "{e:?}"
        );
        assert!(e.to_string().contains(p.name()), "{e}");
    }

    #[test]
    fn inverter_count_is_checked() {
        assert!(matches!(
            eds(Product::Sk550p, 0),
            Err(DescribeError::Inverters { asked: 0, .. })
        ));
        assert!(eds(Product::Tu4Eip, 5).is_err());
        assert!(eds(Product::Tu3Eip, 8).is_ok());
    }

    #[test]
    fn output_is_deterministic_ascii() {
        for p in EIP {
            let a = eds(p, p.max_inverters()).unwrap();
            assert_eq!(a, eds(p, p.max_inverters()).unwrap());
            assert!(a.is_ascii(), "{p:?}");
            assert!(a.contains("CreateDate = 11-23-2026;"));
        }
        assert_eq!(
            ascii("BU 2100 § 7.1.2: 0…3 → µs \"x\""),
            "BU 2100 sec. 7.1.2: 0...3 -> us 'x'"
        );
    }
}
