//! `ros2msg` schemas: the message's `.msg` text followed by its dependencies, each after a line
//! of `=` and a `MSG: pkg/Type` line. Parsed into a table of message types with every field
//! type resolved; constants are skipped, default values ignored.

use std::collections::HashMap;

use crate::error::{Error, Result};

/// A primitive type of the ROS 2 interface definition language.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Prim {
    Bool,
    U8,
    I8,
    I16,
    U16,
    I32,
    U32,
    I64,
    U64,
    F32,
    F64,
}

impl Prim {
    fn from_name(name: &str) -> Option<Self> {
        Some(match name {
            "bool" => Self::Bool,
            "byte" | "char" | "uint8" => Self::U8,
            "int8" => Self::I8,
            "int16" => Self::I16,
            "uint16" => Self::U16,
            "int32" => Self::I32,
            "uint32" => Self::U32,
            "int64" => Self::I64,
            "uint64" => Self::U64,
            "float32" => Self::F32,
            "float64" => Self::F64,
            _ => return None,
        })
    }

    /// Size on the wire, which is also its CDR alignment.
    pub(crate) fn size(self) -> usize {
        match self {
            Self::Bool | Self::U8 | Self::I8 => 1,
            Self::I16 | Self::U16 => 2,
            Self::I32 | Self::U32 | Self::F32 => 4,
            Self::I64 | Self::U64 | Self::F64 => 8,
        }
    }
}

/// A field's element type.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Base {
    Prim(Prim),
    /// `string` or `string<=N` (the bound is not checked on reading).
    Str,
    /// `wstring`: parsed, refused when a decoded message must cross it.
    WStr,
    /// A message type: index into [`Types::msgs`].
    Msg(usize),
}

/// How many elements a field holds.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Array {
    Scalar,
    Fixed(usize),
    Bounded(usize),
    Unbounded,
}

#[derive(Debug, Clone)]
pub(crate) struct FieldDef {
    pub name: String,
    pub base: Base,
    pub array: Array,
}

#[derive(Debug, Clone)]
pub(crate) struct MsgDef {
    /// `pkg/Type`.
    pub name: String,
    pub fields: Vec<FieldDef>,
}

/// A schema's message types, the root first.
#[derive(Debug, Clone)]
pub(crate) struct Types {
    pub msgs: Vec<MsgDef>,
}

/// Nesting deeper than this is refused (no real message comes near; it bounds recursion).
pub(crate) const MAX_DEPTH: usize = 64;

/// Built-in definitions used when a schema leaves them out.
const BUILTIN: &[(&str, &str)] = &[
    ("builtin_interfaces/Time", "int32 sec\nuint32 nanosec\n"),
    ("builtin_interfaces/Duration", "int32 sec\nuint32 nanosec\n"),
];

/// `pkg/msg/Type` → `pkg/Type`.
pub(crate) fn normalise(name: &str) -> String {
    let parts: Vec<&str> = name.split('/').collect();
    match parts.as_slice() {
        [pkg, "msg", ty] => format!("{pkg}/{ty}"),
        _ => name.to_owned(),
    }
}

struct RawField {
    name: String,
    ty: String,
    array: Array,
    line: usize,
    text: String,
}

struct Section {
    name: String,
    fields: Vec<RawField>,
    line: usize,
}

fn is_separator(line: &str) -> bool {
    let t = line.trim();
    t.len() >= 3 && t.bytes().all(|b| b == b'=')
}

/// Parses and resolves a `ros2msg` schema named `schema_name` (e.g. `sensor_msgs/msg/Imu`).
pub(crate) fn parse(schema_name: &str, text: &str) -> Result<Types> {
    let err = |line: usize, t: &str, reason: String| Error::Schema {
        schema: schema_name.to_owned(),
        line,
        text: t.trim().chars().take(120).collect(),
        reason,
    };
    let mut sections = vec![Section { name: normalise(schema_name), fields: Vec::new(), line: 0 }];
    let mut expect_header = false;
    for (i, raw) in text.lines().enumerate() {
        let line_no = i + 1;
        if is_separator(raw) {
            expect_header = true;
            continue;
        }
        let t = raw.trim();
        if t.is_empty() || t.starts_with('#') {
            continue;
        }
        if expect_header {
            let Some(name) = t.strip_prefix("MSG:") else {
                let why = if t.starts_with("IDL:") {
                    "`IDL:` sections (ros2idl) are not supported".to_owned()
                } else {
                    "expected `MSG: pkg/Type` after a separator line".to_owned()
                };
                return Err(err(line_no, raw, why));
            };
            let name = name.trim();
            if name.is_empty() || name.contains(char::is_whitespace) {
                return Err(err(line_no, raw, "a `MSG:` line names one type, `MSG: pkg/Type`".into()));
            }
            sections.push(Section { name: normalise(name), fields: Vec::new(), line: line_no });
            expect_header = false;
            continue;
        }
        if let Some(f) = parse_line(t).map_err(|reason| err(line_no, raw, reason))? {
            let RawLine { name, ty, array } = f;
            // tidy: invariant — `sections` starts with the root section and only grows.
            let section = sections.last_mut().expect("the root section");
            section.fields.push(RawField { name, ty, array, line: line_no, text: raw.to_owned() });
        }
    }
    let mut index: HashMap<String, usize> = HashMap::new();
    for (i, s) in sections.iter().enumerate() {
        if index.insert(s.name.clone(), i).is_some() && i > 0 {
            return Err(err(s.line, &format!("MSG: {}", s.name), format!("`{}` is defined twice", s.name)));
        }
    }
    // Built-in types a schema may leave out.
    for (name, body) in BUILTIN {
        if !index.contains_key(*name) {
            let fields = body
                .lines()
                .filter_map(|l| parse_line(l).ok().flatten())
                .map(|RawLine { name, ty, array }| RawField { name, ty, array, line: 0, text: String::new() })
                .collect();
            index.insert((*name).to_owned(), sections.len());
            sections.push(Section { name: (*name).to_owned(), fields, line: 0 });
        }
    }
    let mut msgs = Vec::with_capacity(sections.len());
    for s in &sections {
        let pkg = s.name.split('/').next().unwrap_or("");
        let mut fields = Vec::with_capacity(s.fields.len());
        for f in &s.fields {
            let base = if let Some(p) = Prim::from_name(&f.ty) {
                Base::Prim(p)
            } else if f.ty == "string" || f.ty.starts_with("string<=") {
                Base::Str
            } else if f.ty == "wstring" || f.ty.starts_with("wstring<=") {
                Base::WStr
            } else {
                let full = match f.ty.matches('/').count() {
                    0 if f.ty == "Header" => "std_msgs/Header".to_owned(),
                    0 => format!("{pkg}/{}", f.ty),
                    _ => normalise(&f.ty),
                };
                match index.get(&full) {
                    Some(&j) => Base::Msg(j),
                    None => {
                        return Err(err(f.line, &f.text, format!("type `{}` is not defined in the schema", f.ty)));
                    }
                }
            };
            fields.push(FieldDef { name: f.name.clone(), base, array: f.array });
        }
        msgs.push(MsgDef { name: s.name.clone(), fields });
    }
    let types = Types { msgs };
    check_depth(&types, &sections, schema_name)?;
    Ok(types)
}

struct RawLine {
    name: String,
    ty: String,
    array: Array,
}

/// One non-comment line: `Ok(None)` for a constant.
fn parse_line(t: &str) -> std::result::Result<Option<RawLine>, String> {
    let t = t.trim();
    let (ty_tok, rest) = t.split_once(char::is_whitespace).ok_or_else(|| "expected `type name`".to_owned())?;
    let rest = rest.trim_start();
    let name_len = rest.find(|c: char| !(c.is_ascii_alphanumeric() || c == '_')).unwrap_or(rest.len());
    let name = &rest[..name_len];
    if name.is_empty() || name.starts_with(|c: char| c.is_ascii_digit()) {
        return Err("expected a field name after the type".to_owned());
    }
    let tail = &rest[name_len..];
    if tail.trim_start().starts_with('=') {
        return Ok(None); // a constant
    }
    if let Some(c) = tail.chars().next().filter(|c| !c.is_whitespace()) {
        return Err(format!("unexpected `{c}` after the field name"));
    }
    let (ty, array) = match ty_tok.find('[') {
        None => (ty_tok, Array::Scalar),
        Some(open) => {
            let inner = ty_tok[open + 1..].strip_suffix(']').ok_or_else(|| format!("bad array type `{ty_tok}`"))?;
            let array = if inner.is_empty() {
                Array::Unbounded
            } else if let Some(n) = inner.strip_prefix("<=") {
                Array::Bounded(n.parse().map_err(|_| format!("bad array bound `{inner}`"))?)
            } else {
                Array::Fixed(inner.parse().map_err(|_| format!("bad array size `{inner}`"))?)
            };
            (&ty_tok[..open], array)
        }
    };
    let valid = |s: &str| !s.is_empty() && s.chars().all(|c| c.is_ascii_alphanumeric() || c == '_');
    let base_name = ty.split("<=").next().unwrap_or(ty);
    let type_ok = base_name.split('/').all(valid) && ty.split("<=").nth(1).is_none_or(|b| b.parse::<usize>().is_ok());
    if !type_ok {
        return Err(format!("bad type `{ty}`"));
    }
    Ok(Some(RawLine { name: name.to_owned(), ty: ty.to_owned(), array }))
}

/// Refuses recursive types and nesting deeper than [`MAX_DEPTH`].
fn check_depth(types: &Types, sections: &[Section], schema_name: &str) -> Result<()> {
    // depth[i]: None unknown, Some(d) done.
    fn visit(types: &Types, i: usize, stack: &mut Vec<usize>, depth: &mut [Option<usize>]) -> Option<usize> {
        if let Some(d) = depth[i] {
            return Some(d);
        }
        if stack.contains(&i) || stack.len() > MAX_DEPTH {
            return None;
        }
        stack.push(i);
        let mut d = 1;
        for f in &types.msgs[i].fields {
            if let Base::Msg(j) = f.base {
                d = d.max(1 + visit(types, j, stack, depth)?);
            }
        }
        stack.pop();
        depth[i] = Some(d);
        Some(d)
    }
    let mut depth = vec![None; types.msgs.len()];
    for i in 0..types.msgs.len() {
        match visit(types, i, &mut Vec::new(), &mut depth) {
            Some(d) if d <= MAX_DEPTH => {}
            _ => {
                return Err(Error::Schema {
                    schema: schema_name.to_owned(),
                    line: sections[i].line,
                    text: String::new(),
                    reason: format!(
                        "type `{}` contains itself or nests deeper than {MAX_DEPTH} levels",
                        types.msgs[i].name
                    ),
                });
            }
        }
    }
    Ok(())
}

/// Largest number of paths listed when fixed arrays are expanded index by index.
const MAX_LISTED: usize = 4096;

impl Types {
    /// The numeric field paths of the root type. `compact`: a fixed array as `a[0..=8]`;
    /// otherwise each index. Variable-length sequences show as `a[i]`.
    pub(crate) fn numeric_paths(&self, compact: bool) -> Vec<String> {
        let mut out = Vec::new();
        self.collect(0, "", compact, &mut out, 0);
        out
    }

    fn collect(&self, msg: usize, prefix: &str, compact: bool, out: &mut Vec<String>, depth: usize) {
        if depth > MAX_DEPTH {
            return;
        }
        for f in &self.msgs[msg].fields {
            if out.len() >= MAX_LISTED {
                if out.last().is_none_or(|l| l != "…") {
                    out.push("…".to_owned());
                }
                return;
            }
            let names: Vec<String> = match f.array {
                Array::Scalar => vec![f.name.clone()],
                Array::Fixed(0) => vec![],
                Array::Fixed(n) if compact => vec![format!("{}[0..={}]", f.name, n - 1)],
                Array::Fixed(n) => (0..n.min(MAX_LISTED)).map(|i| format!("{}[{i}]", f.name)).collect(),
                Array::Bounded(_) | Array::Unbounded => vec![format!("{}[i]", f.name)],
            };
            for name in names {
                match f.base {
                    Base::Prim(_) => out.push(format!("{prefix}{name}")),
                    Base::Msg(j) => self.collect(j, &format!("{prefix}{name}."), compact, out, depth + 1),
                    Base::Str | Base::WStr => {}
                }
                if out.len() >= MAX_LISTED {
                    break;
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const IMU_LIKE: &str = "# comment\nstd_msgs/Header header\nfloat64[9] cov\nfloat64[] data\nint32 FOO=1\nint32 BAR = 2\nstring NAME=\"a # b\"\nuint8 n 5\nstring<=8 label\nint32[<=3] few\n\
================================================================================\nMSG: std_msgs/Header\nbuiltin_interfaces/Time stamp\nstring frame_id\n";

    #[test]
    fn fields_constants_defaults_and_dependencies() {
        let t = parse("pkg/msg/Thing", IMU_LIKE).unwrap();
        assert_eq!(t.msgs[0].name, "pkg/Thing");
        let names: Vec<_> = t.msgs[0].fields.iter().map(|f| f.name.as_str()).collect();
        assert_eq!(names, ["header", "cov", "data", "n", "label", "few"]);
        assert_eq!(t.msgs[0].fields[1].array, Array::Fixed(9));
        assert_eq!(t.msgs[0].fields[5].array, Array::Bounded(3));
        assert_eq!(t.msgs[0].fields[4].base, Base::Str);
        assert_eq!(
            t.numeric_paths(true),
            ["header.stamp.sec", "header.stamp.nanosec", "cov[0..=8]", "data[i]", "n", "few[i]"]
        );
        assert_eq!(t.numeric_paths(false).len(), 2 + 9 + 3);
    }

    #[test]
    fn schema_errors_name_the_line() {
        let e = parse("p/msg/T", "int32 a\nfloat64[x] b\n").unwrap_err();
        assert!(matches!(e, Error::Schema { line: 2, .. }), "{e}");
        let e = parse("p/msg/T", "int32 a\nNoSuch b\n").unwrap_err();
        assert!(matches!(&e, Error::Schema { line: 2, reason, .. } if reason.contains("NoSuch")), "{e}");
        let e = parse("p/msg/T", "int32 a\n====\nint32 b\n").unwrap_err();
        assert!(matches!(e, Error::Schema { line: 3, .. }), "{e}");
        let e = parse("p/msg/T", "p/U u\n===\nMSG: p/U\np/T t\n").unwrap_err();
        assert!(e.to_string().contains("contains itself"), "{e}");
        let e = parse("p/msg/T", "int32\n").unwrap_err();
        assert!(matches!(e, Error::Schema { line: 1, .. }), "{e}");
    }
}
