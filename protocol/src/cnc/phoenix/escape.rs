//! Two-character codes for bytes a part program cannot hold ("Non-Printing Characters").
//!
//! The CNC keeps the pair in the program and sends the single byte. The first character
//! selects the operation on the second:
//!
//! | lead | operation on the 2nd character | second characters | bytes |
//! |---|---|---|---|
//! | `&` | clear 0x40 | `@`..=`_` | 0x00..=0x1F |
//! | `&` | clear 0x40 | `` ` ``..=`z` | 0x20..=0x3A (`&h` = `(`, `&i` = `)`, `&k` = `+`) |
//! | `!` | clear 0x40, set 0x80 | `@`..=`_`, `` ` ``..=`z`, `;`..=`?` | 0x80..=0xBF |
//! | `$` | set 0xC0 | `@`..=`_`, `` ` ``..=`z`, `;`..=`?` | 0xC0..=0xFF |
//!
//! plus `&&` = `&`, `!!` = `!`, `$$` = `$`, `&'` = space and `&?` = DEL (0x7F).
//!
//! Corrections to the OCR'd manual, each by the rule above and the rest of its table:
//! - the text says `$` "clears the 0xC0 bit"; its table (`$@` = C0, `$A` = C1, `$?` = FF) and
//!   its example ("to transmit 0xC1, use `$A`") show that it *sets* 0xC0;
//! - `!_` is listed as 9D: it is 9F (`_` = 0x5F);
//! - `!I` and `$I` are listed twice, once as A9 / E9: those are `!i` and `$i`;
//! - `$Y` is listed as DD: it is D9;
//! - the ESSI note says `&K` sends `+` (0x2B), but its own table gives `&K` = 0x0B and the rule
//!   gives 0x0B too; like `&h` and `&i`, the code for `+` is lower case: `&k`. This module
//!   decodes `&K` as 0x0B and `&k` as `+`.

use crate::{Error, Result};

/// The byte a two-character code stands for, or `None` when the manual defines no such pair.
pub const fn unescape_pair(lead: u8, second: u8) -> Option<u8> {
    if lead == second && (lead == b'&' || lead == b'!' || lead == b'$') {
        return Some(lead);
    }
    match lead {
        b'&' => match second {
            b'\'' => Some(b' '),
            b'?' => Some(0x7F),
            b'@'..=b'z' => Some(second & !0x40),
            _ => None,
        },
        b'!' => match second {
            b';'..=b'z' => Some((second & !0x40) | 0x80),
            _ => None,
        },
        b'$' => match second {
            b';'..=b'z' => Some(second | 0xC0),
            _ => None,
        },
        _ => None,
    }
}

/// Whether `byte` starts a two-character code.
const fn is_lead(byte: u8) -> bool {
    matches!(byte, b'&' | b'!' | b'$')
}

/// Turn the two-character codes of a part-program message into the bytes the CNC sends.
///
/// Other bytes are copied unchanged. Returns the number of bytes written to `out`.
/// Errors: [`Error::Truncated`] for a lead character at the very end, [`Error::Malformed`]
/// for a pair the manual does not define, [`Error::BufferTooSmall`].
pub fn decode_escapes(input: &[u8], out: &mut [u8]) -> Result<usize> {
    let mut written = 0;
    let mut bytes = input.iter().copied();
    while let Some(byte) = bytes.next() {
        let decoded = if is_lead(byte) {
            let second = bytes.next().ok_or(Error::Truncated)?;
            unescape_pair(byte, second).ok_or(Error::Malformed)?
        } else {
            byte
        };
        *out.get_mut(written).ok_or(Error::BufferTooSmall)? = decoded;
        written += 1;
    }
    Ok(written)
}

/// The two characters that stand for `byte`, or `None` when it can be written as itself.
///
/// Besides the non-printing bytes and the three lead characters, `(`, `)` and `+` are
/// written as `&h`, `&i` and `&k` so that the text fits in both a WORD ADDRESS (EIA)
/// comment and an ESSI program.
fn escape_pair(byte: u8) -> Option<[u8; 2]> {
    // Second character for the low six bits of a `!` or `$` code, as the manual's tables
    // write it: 0x00..=0x1F -> `@`..=`_`, 0x20..=0x3A -> `` ` ``..=`z`, 0x3B..=0x3F -> `;`..=`?`.
    const fn high_second(low6: u8) -> u8 {
        if low6 < 0x3B { low6 | 0x40 } else { low6 }
    }
    match byte {
        b'&' | b'!' | b'$' => Some([byte, byte]),
        b'(' => Some(*b"&h"),
        b')' => Some(*b"&i"),
        b'+' => Some(*b"&k"),
        0x7F => Some(*b"&?"),
        0x00..=0x1F => Some([b'&', byte | 0x40]),
        0x80..=0xBF => Some([b'!', high_second(byte & 0x3F)]),
        0xC0..=0xFF => Some([b'$', high_second(byte & 0x3F)]),
        _ => None,
    }
}

/// Write `input` as part-program text: every byte that needs it becomes a two-character
/// code (see [`escape_pair`]'s rules), and a final space becomes `&'` (the manual's code for
/// a space at the end of an ESSI program, where it would otherwise be lost).
///
/// Returns the number of bytes written; [`Error::BufferTooSmall`] when `out` is too short.
/// [`decode_escapes`] turns the result back into `input`.
pub fn encode_escapes(input: &[u8], out: &mut [u8]) -> Result<usize> {
    let mut written = 0;
    let mut put = |bytes: &[u8]| -> Result<()> {
        let end = written + bytes.len();
        out.get_mut(written..end)
            .ok_or(Error::BufferTooSmall)?
            .copy_from_slice(bytes);
        written = end;
        Ok(())
    };
    let last = input.len().checked_sub(1);
    for (i, &byte) in input.iter().enumerate() {
        if byte == b' ' && Some(i) == last {
            put(b"&'")?;
        } else if let Some(pair) = escape_pair(byte) {
            put(&pair)?;
        } else {
            put(&[byte])?;
        }
    }
    Ok(written)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn decode(input: &str) -> Result<heapless::Vec<u8, 64>> {
        let mut out = [0u8; 64];
        let n = decode_escapes(input.as_bytes(), &mut out)?;
        Ok(heapless::Vec::from_slice(&out[..n]).unwrap())
    }

    #[test]
    fn manual_examples() {
        // "To transmit the single character with a value 0x01, use "&A"."
        assert_eq!(&decode("&A").unwrap()[..], &[0x01]);
        // "To transmit 0x81, use "!A" or to transmit 0xC1, use "$A"."
        assert_eq!(&decode("!A").unwrap()[..], &[0x81]);
        assert_eq!(&decode("$A").unwrap()[..], &[0xC1]);
        // ""&&" = "&"" and the same doubling for the other two leads.
        assert_eq!(&decode("&&!!$$").unwrap()[..], b"&!$");
        // The WORD ADDRESS / ESSI codes.
        assert_eq!(&decode("&'").unwrap()[..], b" ");
        assert_eq!(&decode("&h").unwrap()[..], b"(");
        assert_eq!(&decode("&i").unwrap()[..], b")");
        assert_eq!(&decode("&?").unwrap()[..], &[0x7F]);
        // Manual says "&K" = "+"; its table and rule say &K = 0x0B: `+` is `&k` (see module docs).
        assert_eq!(&decode("&K").unwrap()[..], &[0x0B]);
        assert_eq!(&decode("&k").unwrap()[..], b"+");
        assert_eq!(&decode("A&MB&J").unwrap()[..], b"A\rB\n");
    }

    /// The manual's three tables, as printed, with the OCR damage corrected (see module docs).
    #[test]
    fn manual_tables() {
        let low = "&@00 &H08 &P10 &X18 &A01 &I09 &Q11 &Y19 &B02 &J0A &R12 &Z1A &C03 &K0B &S13 \
                   &[1B &D04 &L0C &T14 &\\1C &E05 &M0D &U15 &]1D &F06 &N0E &V16 &^1E &G07 &O0F \
                   &W17 &_1F";
        let bang = "!@80 !H88 !P90 !X98 !A81 !I89 !Q91 !Y99 !B82 !J8A !R92 !Z9A !C83 !K8B !S93 \
                    ![9B !D84 !L8C !T94 !\\9C !E85 !M8D !U95 !]9D !F86 !N8E !V96 !^9E !G87 !O8F \
                    !W97 !_9F !`A0 !hA8 !pB0 !xB8 !aA1 !iA9 !qB1 !yB9 !bA2 !jAA !rB2 !zBA !cA3 \
                    !kAB !sB3 !;BB !dA4 !lAC !tB4 !<BC !eA5 !mAD !uB5 !=BD !fA6 !nAE !vB6 !>BE \
                    !gA7 !oAF !wB7 !?BF";
        let dollar = "$@C0 $HC8 $PD0 $XD8 $AC1 $IC9 $QD1 $YD9 $BC2 $JCA $RD2 $ZDA $CC3 $KCB $SD3 \
                      $[DB $DC4 $LCC $TD4 $\\DC $EC5 $MCD $UD5 $]DD $FC6 $NCE $VD6 $^DE $GC7 $OCF \
                      $WD7 $_DF $`E0 $hE8 $pF0 $xF8 $aE1 $iE9 $qF1 $yF9 $bE2 $jEA $rF2 $zFA $cE3 \
                      $kEB $sF3 $;FB $dE4 $lEC $tF4 $<FC $eE5 $mED $uF5 $=FD $fE6 $nEE $vF6 $>FE \
                      $gE7 $oEF $wF7 $?FF";
        let mut seen = [false; 256];
        for table in [low, bang, dollar] {
            for entry in table.split_whitespace() {
                let e = entry.as_bytes();
                let value = u8::from_str_radix(&entry[2..], 16).unwrap();
                assert_eq!(unescape_pair(e[0], e[1]), Some(value), "{entry}");
                assert!(!seen[value as usize], "{entry} listed twice");
                seen[value as usize] = true;
                // Encoding writes the table's code back (0x00..=0x1F, 0x80..=0xFF).
                let mut out = [0u8; 2];
                assert_eq!(encode_escapes(&[value], &mut out), Ok(2));
                assert_eq!(&out, &e[..2], "{entry}");
            }
        }
        // 32 + 64 + 64 codes: every control byte and every byte from 0x80 up.
        assert!(seen[..0x20].iter().all(|&s| s) && seen[0x80..].iter().all(|&s| s));
    }

    #[test]
    fn undefined_pairs_and_dangling_leads_are_refused() {
        assert_eq!(decode("&1"), Err(Error::Malformed));
        assert_eq!(decode("&{"), Err(Error::Malformed));
        assert_eq!(decode("! "), Err(Error::Malformed));
        assert_eq!(decode("$~"), Err(Error::Malformed));
        assert_eq!(decode("AB&"), Err(Error::Truncated));
        assert_eq!(
            decode_escapes(b"&A&B", &mut [0u8; 1]),
            Err(Error::BufferTooSmall)
        );
    }

    #[test]
    fn encode_round_trips_every_byte() {
        let all: [u8; 256] = core::array::from_fn(|i| i as u8);
        let mut text = [0u8; 512];
        let n = encode_escapes(&all, &mut text).unwrap();
        assert!(text[..n].iter().all(|b| (0x20..0x7F).contains(b)));
        assert!(!text[..n].iter().any(|b| matches!(b, b'(' | b')' | b'+')));
        let mut back = [0u8; 256];
        assert_eq!(decode_escapes(&text[..n], &mut back), Ok(256));
        assert_eq!(back, all);
        // A final space is written as &'.
        let mut out = [0u8; 8];
        let n = encode_escapes(b"A B ", &mut out).unwrap();
        assert_eq!(&out[..n], b"A B&'");
        assert_eq!(
            encode_escapes(b"&", &mut [0u8; 1]),
            Err(Error::BufferTooSmall)
        );
    }
}
