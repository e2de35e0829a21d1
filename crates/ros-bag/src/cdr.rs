//! CDR messages (XCDR1, as ROS 2 writes them): a 4-byte encapsulation header (`00 01`
//! little-endian, `00 00` big-endian), then the fields in order, each primitive aligned to its
//! size counted from the end of the header; strings and sequences prefixed by a `uint32` length
//! (a string's counts its NUL). A message is walked field by field and only the selected
//! numbers are kept; every length is checked against the bytes left before it is used.

use crate::msgdef::{Array, Base, MAX_DEPTH, Prim, Types};
use crate::path::Segment;

/// What a selected path leads to, inside one field.
#[derive(Debug, Clone)]
enum Node {
    /// A number: the output slots that take it.
    Leaf(Vec<usize>),
    /// Fields of a nested message.
    Struct(SelStruct),
}

#[derive(Debug, Clone)]
enum FieldSel {
    /// A scalar field.
    Whole(Node),
    /// Elements of an array field, by index (sorted).
    Elements(Vec<(usize, Node)>),
}

/// The selected fields of one message type, by field index.
#[derive(Debug, Clone, Default)]
struct SelStruct {
    fields: Vec<Option<FieldSel>>,
}

/// Why a path does not select a number.
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum Unresolved {
    /// No such field, index out of range, a message where a number was asked, …
    Unknown(String),
    /// A string field.
    NonNumeric(String),
}

/// A compiled selection of numeric fields from one message type.
#[derive(Debug, Clone)]
pub(crate) struct Plan {
    types: Types,
    root: SelStruct,
}

/// A message that does not decode.
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum DecodeError {
    /// The bytes do not follow the schema.
    Corrupt(String),
    /// A selected field is not in this message (output `slot`).
    Missing { slot: usize, reason: String },
    /// A selected field holds no number in this message (output `slot`).
    NonNumeric { slot: usize, found: String },
}

fn fail<T>(reason: impl Into<String>) -> Result<T, DecodeError> {
    Err(DecodeError::Corrupt(reason.into()))
}

impl Plan {
    /// A plan selecting nothing yet; refuses types with a `wstring` anywhere (its size on the
    /// wire depends on the writer's `wchar_t`).
    pub(crate) fn new(types: Types) -> Result<Self, String> {
        for m in &types.msgs {
            if let Some(f) = m.fields.iter().find(|f| f.base == Base::WStr) {
                return Err(format!("field `{}` of `{}` is a wstring: not supported", f.name, m.name));
            }
        }
        let root = SelStruct { fields: vec![None; types.msgs[0].fields.len()] };
        Ok(Self { types, root })
    }

    pub(crate) fn types(&self) -> &Types {
        &self.types
    }

    /// Adds `path`, whose number goes to output `slot`.
    pub(crate) fn select(&mut self, path: &[Segment], slot: usize) -> Result<(), Unresolved> {
        insert(&self.types, 0, &mut self.root, path, slot)
    }

    /// Decodes `data` (a whole CDR message, header included) into `out` (selected slots only).
    pub(crate) fn decode(&self, data: &[u8], out: &mut [f64]) -> Result<(), DecodeError> {
        if data.len() < 4 {
            return fail(format!("{} bytes: shorter than the 4-byte CDR header", data.len()));
        }
        let le = match (data[0], data[1]) {
            (0, 1) | (0, 3) => true,
            (0, 0) | (0, 2) => false,
            (a, b) => return fail(format!("encapsulation header {a:#04x} {b:#04x} is not plain CDR")),
        };
        let mut rd = Rd { b: &data[4..], pos: 0, le };
        walk(&self.types, 0, Some(&self.root), &mut rd, out, 0)
    }
}

fn inconsistent() -> Unresolved {
    Unresolved::Unknown("inconsistent selection".into())
}

/// Adds `path` (relative to message type `msg`, selected by `sel`) for output `slot`.
fn insert(types: &Types, msg: usize, sel: &mut SelStruct, path: &[Segment], slot: usize) -> Result<(), Unresolved> {
    let Some((seg, rest)) = path.split_first() else { return Err(Unresolved::Unknown("empty path".into())) };
    let def = &types.msgs[msg];
    let Some(fi) = def.fields.iter().position(|f| f.name == seg.name) else {
        return Err(Unresolved::Unknown(format!("`{}` has no field `{}`", def.name, seg.name)));
    };
    let f = &def.fields[fi];
    let fresh = || match f.base {
        Base::Msg(j) => Node::Struct(SelStruct { fields: vec![None; types.msgs[j].fields.len()] }),
        _ => Node::Leaf(Vec::new()),
    };
    let node: &mut Node = match (f.array, seg.index) {
        (Array::Scalar, Some(_)) => return Err(Unresolved::Unknown(format!("`{}` is not an array", seg.name))),
        (Array::Scalar, None) => match sel.fields[fi].get_or_insert_with(|| FieldSel::Whole(fresh())) {
            FieldSel::Whole(n) => n,
            FieldSel::Elements(_) => return Err(inconsistent()),
        },
        (_, None) => {
            return Err(Unresolved::Unknown(format!("`{}` is an array: give an index, `{}[0]`", seg.name, seg.name)));
        }
        (Array::Fixed(n) | Array::Bounded(n), Some(i)) if i >= n => {
            return Err(Unresolved::Unknown(format!("`{}` holds at most {n} elements", seg.name)));
        }
        (_, Some(i)) => {
            let FieldSel::Elements(els) = sel.fields[fi].get_or_insert_with(|| FieldSel::Elements(Vec::new())) else {
                return Err(inconsistent());
            };
            let at = match els.binary_search_by_key(&i, |(j, _)| *j) {
                Ok(at) => at,
                Err(at) => {
                    els.insert(at, (i, fresh()));
                    at
                }
            };
            &mut els[at].1
        }
    };
    match (f.base, rest.is_empty(), node) {
        (Base::Prim(_), true, Node::Leaf(v)) => {
            v.push(slot);
            Ok(())
        }
        (Base::Str | Base::WStr, true, _) => Err(Unresolved::NonNumeric("string".into())),
        (Base::Msg(j), true, _) => {
            Err(Unresolved::Unknown(format!("`{}` is a message ({}), not a number", seg.name, types.msgs[j].name)))
        }
        (Base::Msg(j), false, Node::Struct(s)) => insert(types, j, s, rest, slot),
        (Base::Prim(_) | Base::Str | Base::WStr, false, _) => {
            Err(Unresolved::Unknown(format!("`{}` is a number: it has no fields", seg.name)))
        }
        _ => Err(inconsistent()),
    }
}

struct Rd<'a> {
    b: &'a [u8],
    pos: usize,
    le: bool,
}

impl Rd<'_> {
    fn remaining(&self) -> usize {
        self.b.len() - self.pos
    }

    fn align(&mut self, n: usize) -> Result<(), DecodeError> {
        let p = self.pos.next_multiple_of(n);
        if p > self.b.len() {
            return fail(format!("ends at byte {} inside padding", self.b.len() + 4));
        }
        self.pos = p;
        Ok(())
    }

    fn skip(&mut self, n: usize, what: &str) -> Result<(), DecodeError> {
        if n > self.remaining() {
            return fail(format!(
                "{what} of {n} bytes at byte {} runs past the end ({} bytes)",
                self.pos + 4,
                self.b.len() + 4
            ));
        }
        self.pos += n;
        Ok(())
    }

    fn bytes<const N: usize>(&mut self) -> Result<[u8; N], DecodeError> {
        self.align(N)?;
        let Some(s) = self.b.get(self.pos..self.pos + N) else {
            return fail(format!(
                "a {N}-byte number at byte {} runs past the end ({} bytes)",
                self.pos + 4,
                self.b.len() + 4
            ));
        };
        let mut a = [0; N];
        a.copy_from_slice(s);
        if !self.le {
            a.reverse();
        }
        self.pos += N;
        Ok(a)
    }

    fn u32(&mut self) -> Result<u32, DecodeError> {
        Ok(u32::from_le_bytes(self.bytes::<4>()?))
    }

    fn prim(&mut self, p: Prim) -> Result<f64, DecodeError> {
        Ok(match p {
            Prim::Bool => f64::from(u8::from(self.bytes::<1>()?[0] != 0)),
            Prim::U8 => f64::from(self.bytes::<1>()?[0]),
            Prim::I8 => f64::from(i8::from_le_bytes(self.bytes::<1>()?)),
            Prim::I16 => f64::from(i16::from_le_bytes(self.bytes::<2>()?)),
            Prim::U16 => f64::from(u16::from_le_bytes(self.bytes::<2>()?)),
            Prim::I32 => f64::from(i32::from_le_bytes(self.bytes::<4>()?)),
            Prim::U32 => f64::from(u32::from_le_bytes(self.bytes::<4>()?)),
            Prim::I64 => i64::from_le_bytes(self.bytes::<8>()?) as f64,
            Prim::U64 => u64::from_le_bytes(self.bytes::<8>()?) as f64,
            Prim::F32 => f64::from(f32::from_le_bytes(self.bytes::<4>()?)),
            Prim::F64 => f64::from_le_bytes(self.bytes::<8>()?),
        })
    }
}

/// Reads one element of type `base`: a number into `node`'s slots, a message through `node`.
fn element(
    types: &Types,
    base: Base,
    node: Option<&Node>,
    rd: &mut Rd<'_>,
    out: &mut [f64],
    depth: usize,
) -> Result<(), DecodeError> {
    match base {
        Base::Prim(p) => {
            let v = rd.prim(p)?;
            if let Some(Node::Leaf(slots)) = node {
                for &s in slots {
                    out[s] = v;
                }
            }
            Ok(())
        }
        Base::Str => {
            let n = rd.u32()? as usize;
            rd.skip(n, "a string")
        }
        Base::WStr => fail("wstring fields are not supported"),
        Base::Msg(j) => {
            let sel = match node {
                Some(Node::Struct(s)) => Some(s),
                _ => None,
            };
            walk(types, j, sel, rd, out, depth + 1)
        }
    }
}

fn walk(
    types: &Types,
    msg: usize,
    sel: Option<&SelStruct>,
    rd: &mut Rd<'_>,
    out: &mut [f64],
    depth: usize,
) -> Result<(), DecodeError> {
    if depth > MAX_DEPTH {
        return fail("nested too deep");
    }
    let def = &types.msgs[msg];
    if def.fields.is_empty() {
        // ROS 2 gives an empty message one `uint8 structure_needs_at_least_one_member`.
        return rd.skip(1, "an empty message's placeholder byte");
    }
    for (fi, f) in def.fields.iter().enumerate() {
        let fsel = sel.and_then(|s| s.fields.get(fi)).and_then(Option::as_ref);
        let count = match f.array {
            Array::Scalar => {
                let node = match fsel {
                    Some(FieldSel::Whole(n)) => Some(n),
                    _ => None,
                };
                element(types, f.base, node, rd, out, depth)?;
                continue;
            }
            Array::Fixed(n) => n,
            Array::Bounded(bound) => {
                let n = rd.u32()? as usize;
                if n > bound {
                    return fail(format!("sequence `{}` holds {n} elements, more than its bound {bound}", f.name));
                }
                n
            }
            Array::Unbounded => rd.u32()? as usize,
        };
        let els: &[(usize, Node)] = match fsel {
            Some(FieldSel::Elements(e)) => e,
            _ => &[],
        };
        // Every element takes at least one byte: a count beyond the bytes left is corrupt.
        if count > rd.remaining() {
            return fail(format!("array `{}` claims {count} elements with {} bytes left", f.name, rd.remaining()));
        }
        if let Some(&(i, _)) = els.iter().find(|(i, _)| *i >= count) {
            let slot = first_slot(els.iter().find(|(j, _)| *j == i).map(|(_, n)| n)).unwrap_or(0);
            return Err(DecodeError::Missing {
                slot,
                reason: format!("index {i} is past the end of `{}`, which holds {count} elements here", f.name),
            });
        }
        match f.base {
            Base::Prim(p) if els.is_empty() => {
                if count > 0 {
                    rd.align(p.size())?;
                    // tidy: invariant — count ≤ remaining bytes, so the product fits in usize.
                    rd.skip(count.checked_mul(p.size()).expect("count ≤ remaining"), "an array")?;
                }
            }
            Base::Prim(p) => {
                if count > 0 {
                    rd.align(p.size())?;
                    if count.saturating_mul(p.size()) > rd.remaining() {
                        return fail(format!("array `{}` of {count} elements runs past the end", f.name));
                    }
                }
                let start = rd.pos;
                for &(i, ref node) in els {
                    rd.pos = start + i * p.size();
                    element(types, f.base, Some(node), rd, out, depth)?;
                }
                rd.pos = start + count * p.size();
            }
            _ => {
                let mut next = els.iter().peekable();
                for i in 0..count {
                    let node = match next.peek() {
                        Some((j, n)) if *j == i => {
                            next.next();
                            Some(n)
                        }
                        _ => None,
                    };
                    element(types, f.base, node, rd, out, depth)?;
                }
            }
        }
    }
    Ok(())
}

fn first_slot(node: Option<&Node>) -> Option<usize> {
    match node? {
        Node::Leaf(v) => v.first().copied(),
        Node::Struct(s) => s.fields.iter().flatten().find_map(|f| match f {
            FieldSel::Whole(n) => first_slot(Some(n)),
            FieldSel::Elements(e) => e.iter().find_map(|(_, n)| first_slot(Some(n))),
        }),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::msgdef;
    use crate::path;

    fn plan(text: &str, fields: &[&str]) -> Plan {
        let mut p = Plan::new(msgdef::parse("t/msg/T", text).unwrap()).unwrap();
        for (slot, f) in fields.iter().enumerate() {
            p.select(&path::parse("k", f).unwrap(), slot).unwrap();
        }
        p
    }

    #[test]
    fn both_byte_orders_and_alignment_after_the_header() {
        let p = plan("uint8 a\nfloat64 b\nstring s\nint16[2] c\nbool d\n", &["a", "b", "c[1]", "d"]);
        let mut le = vec![0, 1, 0, 0, 7, 0, 0, 0, 0, 0, 0, 0];
        le.extend_from_slice(&2.5f64.to_le_bytes());
        le.extend_from_slice(&[3, 0, 0, 0, b'h', b'i', 0, 0]);
        le.extend_from_slice(&[1, 0, 0xfe, 0xff, 1]);
        let mut be = vec![0, 0, 0, 0, 7, 0, 0, 0, 0, 0, 0, 0];
        be.extend_from_slice(&2.5f64.to_be_bytes());
        be.extend_from_slice(&[0, 0, 0, 3, b'h', b'i', 0, 0]);
        be.extend_from_slice(&[0, 1, 0xff, 0xfe, 1]);
        for data in [le, be] {
            let mut out = [0.0; 4];
            p.decode(&data, &mut out).unwrap();
            assert_eq!(out, [7.0, 2.5, -2.0, 1.0]);
        }
    }

    #[test]
    fn an_empty_message_takes_one_byte_and_a_bounded_sequence_is_checked() {
        let p = plan("t/E e\nuint8 x\nint32[<=2] s\n===\nMSG: t/E\n", &["x"]);
        let mut out = [0.0];
        p.decode(&[0, 1, 0, 0, 0, 9, 0, 0, 0, 0, 0, 0], &mut out).unwrap();
        assert_eq!(out, [9.0]);
        let e = p.decode(&[0, 1, 0, 0, 0, 9, 0, 0, 3, 0, 0, 0], &mut out).unwrap_err();
        assert!(matches!(e, DecodeError::Corrupt(r) if r.contains("bound 2")));
        assert!(matches!(p.decode(&[0, 1], &mut out), Err(DecodeError::Corrupt(_))));
        assert!(matches!(p.decode(&[0, 9, 0, 0, 1], &mut out), Err(DecodeError::Corrupt(_))));
    }
}
