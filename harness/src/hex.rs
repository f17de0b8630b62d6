//! Bytes as the transcripts, reports and error messages write them: `70 66 02 00`. A leaf
//! module: every bus and the reports use it, and it uses nothing of the harness.

/// Bytes as `"70 66 02 00"` (one allocation: it runs for every exchange of a run).
pub(crate) fn hex(bytes: &[u8]) -> String {
    const DIGITS: &[u8; 16] = b"0123456789ABCDEF";
    let mut s = Vec::with_capacity(bytes.len() * 3);
    for b in bytes {
        s.extend_from_slice(&[
            DIGITS[usize::from(b >> 4)],
            DIGITS[usize::from(b & 0x0F)],
            b' ',
        ]);
    }
    s.pop();
    // ASCII digits and spaces only.
    String::from_utf8(s).unwrap_or_default()
}

/// A CAN frame as transcripts and `system-bus` observations show it: the COB-ID, then the data
/// bytes (`604 40 00 20 00 00 00 00 00`).
pub(crate) fn can_frame(f: &proto::can::CanFrame) -> String {
    if f.data().is_empty() {
        format!("{:03X}", f.id())
    } else {
        format!("{:03X} {}", f.id(), hex(f.data()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bytes_are_upper_case_pairs_between_single_spaces() {
        assert_eq!(hex(&[0x70, 0x66, 0x02, 0x0A]), "70 66 02 0A");
        assert_eq!(hex(&[]), "");
    }
}
