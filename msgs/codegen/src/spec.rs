//! The parsed form of ROS 2 `.msg` and `.srv` files.
//!
//! The grammar is the one `rosidl_adapter` accepts for the features this project uses:
//! primitive and nested fields, fixed arrays `T[N]`, bounded `T[<=N]` and unbounded `T[]`
//! sequences, bounded strings `string<=N`, scalar default values and constants. Anything else
//! (wide strings, array default values) is refused with the file and line, never guessed at.

use std::fmt;

/// A fully qualified interface type name: `package/kind/Name` (kind is `msg` or `srv`).
#[derive(Debug, Clone, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct TypeName {
    /// ROS package, e.g. `sensor_msgs`.
    pub package: String,
    /// `msg` or `srv`.
    pub kind: String,
    /// Type name, e.g. `JointState` or `Reset_Request`.
    pub name: String,
}

impl TypeName {
    /// A message type `package/msg/name`.
    pub fn msg(package: &str, name: &str) -> Self {
        Self::new(package, "msg", name)
    }

    /// A type with an explicit kind.
    pub fn new(package: &str, kind: &str, name: &str) -> Self {
        TypeName {
            package: package.into(),
            kind: kind.into(),
            name: name.into(),
        }
    }

    /// The DDS type name the ROS 2 RMWs register: `pkg::kind::dds_::Name_`.
    pub fn dds_name(&self) -> String {
        format!("{}::{}::dds_::{}_", self.package, self.kind, self.name)
    }
}

impl fmt::Display for TypeName {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}/{}/{}", self.package, self.kind, self.name)
    }
}

/// The primitive types of the ROS 2 interface language.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[allow(missing_docs)]
pub enum Primitive {
    Bool,
    Byte,
    Char,
    Int8,
    UInt8,
    Int16,
    UInt16,
    Int32,
    UInt32,
    Int64,
    UInt64,
    Float32,
    Float64,
}

impl Primitive {
    /// Parse a primitive type keyword.
    pub fn from_keyword(word: &str) -> Option<Self> {
        Some(match word {
            "bool" => Self::Bool,
            "byte" => Self::Byte,
            "char" => Self::Char,
            "int8" => Self::Int8,
            "uint8" => Self::UInt8,
            "int16" => Self::Int16,
            "uint16" => Self::UInt16,
            "int32" => Self::Int32,
            "uint32" => Self::UInt32,
            "int64" => Self::Int64,
            "uint64" => Self::UInt64,
            "float32" => Self::Float32,
            "float64" => Self::Float64,
            _ => return None,
        })
    }

    /// The keyword as written in a `.msg` file.
    pub fn keyword(self) -> &'static str {
        match self {
            Self::Bool => "bool",
            Self::Byte => "byte",
            Self::Char => "char",
            Self::Int8 => "int8",
            Self::UInt8 => "uint8",
            Self::Int16 => "int16",
            Self::UInt16 => "uint16",
            Self::Int32 => "int32",
            Self::UInt32 => "uint32",
            Self::Int64 => "int64",
            Self::UInt64 => "uint64",
            Self::Float32 => "float32",
            Self::Float64 => "float64",
        }
    }

    /// The Rust type that holds it (`byte` and `char` are octets in ROS 2).
    pub fn rust_type(self) -> &'static str {
        match self {
            Self::Bool => "bool",
            Self::Byte | Self::Char | Self::UInt8 => "u8",
            Self::Int8 => "i8",
            Self::Int16 => "i16",
            Self::UInt16 => "u16",
            Self::Int32 => "i32",
            Self::UInt32 => "u32",
            Self::Int64 => "i64",
            Self::UInt64 => "u64",
            Self::Float32 => "f32",
            Self::Float64 => "f64",
        }
    }

    /// Inclusive integer range, for checking default and constant values.
    pub fn integer_range(self) -> Option<(i128, i128)> {
        Some(match self {
            Self::Byte | Self::Char | Self::UInt8 => (0, u8::MAX as i128),
            Self::Int8 => (i8::MIN as i128, i8::MAX as i128),
            Self::Int16 => (i16::MIN as i128, i16::MAX as i128),
            Self::UInt16 => (0, u16::MAX as i128),
            Self::Int32 => (i32::MIN as i128, i32::MAX as i128),
            Self::UInt32 => (0, u32::MAX as i128),
            Self::Int64 => (i64::MIN as i128, i64::MAX as i128),
            Self::UInt64 => (0, u64::MAX as i128),
            Self::Bool | Self::Float32 | Self::Float64 => return None,
        })
    }
}

/// The element type of a field, before any array suffix.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum BaseType {
    /// A primitive number or bool.
    Primitive(Primitive),
    /// A UTF-8 string, optionally bounded to `bound` bytes.
    String {
        /// `Some(n)` for `string<=n`.
        bound: Option<usize>,
    },
    /// Another message type.
    Nested {
        /// Resolved full name.
        name: TypeName,
        /// As written in the referring file, package-qualified (`pkg/Type`): what rosbag2 puts
        /// after `MSG: ` in a stored definition.
        written: String,
    },
}

/// Array-ness of a field.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ArrayKind {
    /// A single value.
    Single,
    /// `T[N]`: exactly N elements, no length on the wire.
    Fixed(usize),
    /// `T[<=N]`: at most N elements, length on the wire.
    Bounded(usize),
    /// `T[]`: any number of elements, length on the wire.
    Unbounded,
}

/// A field's full type.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct FieldType {
    /// Element type.
    pub base: BaseType,
    /// Array suffix.
    pub array: ArrayKind,
}

/// A literal value given for a default or a constant.
#[derive(Debug, Clone, PartialEq)]
pub enum Literal {
    /// `true` / `false`.
    Bool(bool),
    /// An integer, range-checked against its type.
    Int(i128),
    /// A float (also used for integer-looking literals of float fields).
    Float(f64),
    /// A string, unquoted.
    Str(String),
}

/// One field of a message.
#[derive(Debug, Clone, PartialEq)]
pub struct Field {
    /// Field name (lower snake case).
    pub name: String,
    /// Field type.
    pub ty: FieldType,
    /// Default value, if the file gives one.
    pub default: Option<Literal>,
    /// Comment lines attached to the field (preceding block and trailing comment).
    pub doc: Vec<String>,
}

/// One constant of a message.
#[derive(Debug, Clone, PartialEq)]
pub struct Constant {
    /// Constant name (upper snake case).
    pub name: String,
    /// Type: a primitive or an unbounded string.
    pub ty: BaseType,
    /// Value.
    pub value: Literal,
    /// Comment lines attached to the constant.
    pub doc: Vec<String>,
}

/// A message: a `.msg` file, or one half of a `.srv` file.
#[derive(Debug, Clone, PartialEq)]
pub struct MessageSpec {
    /// Full name.
    pub name: TypeName,
    /// Fields in file order (= CDR order).
    pub fields: Vec<Field>,
    /// Constants in file order.
    pub constants: Vec<Constant>,
    /// The source text verbatim (for a `.srv`, the lines of that half).
    pub text: String,
    /// The comment block at the top of the file, before the first field or constant.
    pub doc: Vec<String>,
}

/// A service: a `.srv` file.
#[derive(Debug, Clone, PartialEq)]
pub struct ServiceSpec {
    /// Full name, kind `srv`.
    pub name: TypeName,
    /// `Name_Request`.
    pub request: MessageSpec,
    /// `Name_Response`.
    pub response: MessageSpec,
}

/// An action: a `.action` file.
#[derive(Debug, Clone, PartialEq)]
pub struct ActionSpec {
    /// Full name, kind `action`.
    pub name: TypeName,
    /// `Name_Goal`.
    pub goal: MessageSpec,
    /// `Name_Result`.
    pub result: MessageSpec,
    /// `Name_Feedback`.
    pub feedback: MessageSpec,
}

/// A parse error, with the file and line it refers to.
#[derive(Debug, Clone, PartialEq)]
pub struct ParseError {
    /// Path or type name of the file.
    pub file: String,
    /// 1-based line number.
    pub line: usize,
    /// What is wrong and what would be valid.
    pub message: String,
}

impl fmt::Display for ParseError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}:{}: {}", self.file, self.line, self.message)
    }
}

impl std::error::Error for ParseError {}

/// Parse the text of a `.msg` file.
pub fn parse_message(name: TypeName, text: &str) -> Result<MessageSpec, ParseError> {
    parse_lines(name, text, 0)
}

/// Parse the text of a `.srv` file into its request and response halves.
pub fn parse_service(name: TypeName, text: &str) -> Result<ServiceSpec, ParseError> {
    let [request, response] = parse_parts(&name, text, "srv", ["Request", "Response"])?;
    Ok(ServiceSpec {
        name,
        request,
        response,
    })
}

/// Parse the text of a `.action` file into its goal, result and feedback parts.
pub fn parse_action(name: TypeName, text: &str) -> Result<ActionSpec, ParseError> {
    let [goal, result, feedback] =
        parse_parts(&name, text, "action", ["Goal", "Result", "Feedback"])?;
    Ok(ActionSpec {
        name,
        goal,
        result,
        feedback,
    })
}

/// The `---`-separated parts of a `.srv` or `.action` file, as messages `Name_<suffix>`.
fn parse_parts<const N: usize>(
    name: &TypeName,
    text: &str,
    kind: &str,
    suffixes: [&str; N],
) -> Result<[MessageSpec; N], ParseError> {
    let lines: Vec<&str> = text.split_inclusive('\n').collect();
    let separators: Vec<usize> = lines
        .iter()
        .enumerate()
        .filter(|(_, l)| l.trim() == "---")
        .map(|(i, _)| i)
        .collect();
    if separators.len() != N - 1 {
        return Err(ParseError {
            file: name.to_string(),
            line: separators.get(N - 1).map_or(lines.len(), |i| i + 1),
            message: format!(
                "a .{kind} file needs exactly {} `---` line(s) between its parts ({}), found {}",
                N - 1,
                suffixes.join(", ").to_lowercase(),
                separators.len()
            ),
        });
    }
    let mut parts = Vec::with_capacity(N);
    let mut start = 0;
    for (index, suffix) in suffixes.iter().enumerate() {
        let end = separators.get(index).copied().unwrap_or(lines.len());
        let part_name = TypeName::new(&name.package, kind, &format!("{}_{suffix}", name.name));
        parts.push(parse_lines(part_name, &lines[start..end].concat(), start)?);
        start = end + 1;
    }
    Ok(parts.try_into().expect("one part per suffix"))
}

fn parse_lines(name: TypeName, text: &str, line_offset: usize) -> Result<MessageSpec, ParseError> {
    let mut spec = MessageSpec {
        name: name.clone(),
        fields: Vec::new(),
        constants: Vec::new(),
        text: text.to_string(),
        doc: Vec::new(),
    };
    let mut pending_doc: Vec<String> = Vec::new();
    let mut seen_member = false;
    for (index, raw_line) in text.lines().enumerate() {
        let line_no = line_offset + index + 1;
        let err = |message: String| ParseError {
            file: name.to_string(),
            line: line_no,
            message,
        };
        let trimmed = raw_line.trim();
        if trimmed.is_empty() {
            // A blank line ends the file's leading comment block.
            if !seen_member && spec.doc.is_empty() {
                spec.doc = std::mem::take(&mut pending_doc);
            } else {
                pending_doc.clear();
            }
            continue;
        }
        if let Some(comment) = trimmed.strip_prefix('#') {
            pending_doc.push(comment.strip_prefix(' ').unwrap_or(comment).to_string());
            continue;
        }
        seen_member = true;
        let (type_token, rest) = split_word(trimmed);
        let (ty, is_constant_capable) = parse_type(type_token, &name.package).map_err(err)?;
        let rest = rest.trim_start();
        if rest.is_empty() {
            return Err(err(format!("`{type_token}` has no field name after it")));
        }
        // Constants are `TYPE NAME=VALUE`; fields are `TYPE name [DEFAULT] [# comment]`.
        let name_end = rest
            .find(|c: char| c.is_whitespace() || c == '=')
            .unwrap_or(rest.len());
        let member_name = &rest[..name_end];
        let after_name = rest[name_end..].trim_start();
        let mut doc = std::mem::take(&mut pending_doc);
        if let Some(value_text) = after_name.strip_prefix('=') {
            if !is_constant_capable || ty.array != ArrayKind::Single {
                return Err(err(format!(
                    "constant `{member_name}` must have a primitive or string type, not `{type_token}`"
                )));
            }
            check_constant_name(member_name).map_err(err)?;
            let (value_text, comment) = split_comment(value_text, &ty.base);
            doc.extend(comment);
            let value = parse_literal(value_text.trim(), &ty.base).map_err(err)?;
            spec.constants.push(Constant {
                name: member_name.into(),
                ty: ty.base,
                value,
                doc,
            });
        } else {
            check_field_name(member_name).map_err(err)?;
            let (default_text, comment) = split_comment(after_name, &ty.base);
            doc.extend(comment);
            let default_text = default_text.trim();
            let default = if default_text.is_empty() {
                None
            } else if ty.array != ArrayKind::Single {
                return Err(err(format!(
                    "default values for array field `{member_name}` are not supported; \
                     remove `{default_text}`"
                )));
            } else if !is_constant_capable {
                return Err(err(format!(
                    "nested field `{member_name}` cannot have a default value"
                )));
            } else {
                Some(parse_literal(default_text, &ty.base).map_err(err)?)
            };
            if spec.fields.iter().any(|f| f.name == member_name)
                || spec.constants.iter().any(|c| c.name == member_name)
            {
                return Err(err(format!("`{member_name}` is defined twice")));
            }
            spec.fields.push(Field {
                name: member_name.into(),
                ty,
                default,
                doc,
            });
        }
    }
    if !seen_member && spec.doc.is_empty() {
        spec.doc = pending_doc;
    }
    Ok(spec)
}

fn split_word(s: &str) -> (&str, &str) {
    let end = s.find(char::is_whitespace).unwrap_or(s.len());
    (&s[..end], &s[end..])
}

/// Split a trailing `# comment` off a value; inside a string value a `#` is data.
fn split_comment<'a>(s: &'a str, base: &BaseType) -> (&'a str, Option<String>) {
    let search_from = if matches!(base, BaseType::String { .. }) {
        let t = s.trim_start();
        let offset = s.len() - t.len();
        match t.chars().next() {
            Some(q @ ('"' | '\'')) => t[1..].find(q).map_or(s.len(), |i| offset + i + 2),
            _ => 0,
        }
    } else {
        0
    };
    match s[search_from..].find('#') {
        Some(i) => {
            let comment = s[search_from + i + 1..].trim();
            (
                &s[..search_from + i],
                (!comment.is_empty()).then(|| comment.to_string()),
            )
        }
        None => (s, None),
    }
}

/// Parse a type token; the bool says whether it may carry a default or be a constant.
fn parse_type(token: &str, package: &str) -> Result<(FieldType, bool), String> {
    let (base_token, array) = match token.find('[') {
        Some(open) => {
            let inner = token[open + 1..]
                .strip_suffix(']')
                .ok_or_else(|| format!("`{token}`: array suffix must end with `]`"))?;
            let array = if inner.is_empty() {
                ArrayKind::Unbounded
            } else if let Some(bound) = inner.strip_prefix("<=") {
                ArrayKind::Bounded(parse_size(bound, token)?)
            } else {
                ArrayKind::Fixed(parse_size(inner, token)?)
            };
            (&token[..open], array)
        }
        None => (token, ArrayKind::Single),
    };
    if let Some(primitive) = Primitive::from_keyword(base_token) {
        return Ok((
            FieldType {
                base: BaseType::Primitive(primitive),
                array,
            },
            true,
        ));
    }
    if base_token == "string" {
        return Ok((
            FieldType {
                base: BaseType::String { bound: None },
                array,
            },
            true,
        ));
    }
    if let Some(bound) = base_token.strip_prefix("string<=") {
        let bound = Some(parse_size(bound, token)?);
        return Ok((
            FieldType {
                base: BaseType::String { bound },
                array,
            },
            true,
        ));
    }
    if base_token.starts_with("wstring") || base_token == "wchar" {
        return Err(format!(
            "`{token}`: wide strings are not supported; use `string`"
        ));
    }
    if matches!(base_token, "float128" | "time" | "duration" | "Header") {
        return Err(format!(
            "`{token}` is not a ROS 2 type (ROS 1 names?); use builtin_interfaces/Time, \
             builtin_interfaces/Duration or std_msgs/Header"
        ));
    }
    let (pkg, type_name) = match base_token.split_once('/') {
        Some((pkg, type_name)) => (pkg, type_name),
        None => (package, base_token),
    };
    let valid_package = !pkg.is_empty()
        && pkg
            .chars()
            .all(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || c == '_');
    let valid_type = type_name
        .chars()
        .next()
        .is_some_and(|c| c.is_ascii_uppercase())
        && type_name.chars().all(|c| c.is_ascii_alphanumeric());
    if !valid_package || !valid_type {
        return Err(format!(
            "`{token}` is neither a primitive (bool, byte, char, int8..uint64, float32, float64, \
             string) nor a message type `package/Type`"
        ));
    }
    let base = BaseType::Nested {
        name: TypeName::msg(pkg, type_name),
        written: format!("{pkg}/{type_name}"),
    };
    Ok((FieldType { base, array }, false))
}

fn parse_size(text: &str, token: &str) -> Result<usize, String> {
    match text.parse::<usize>() {
        Ok(n) if n > 0 => Ok(n),
        _ => Err(format!(
            "`{token}`: array or string bound must be a positive integer"
        )),
    }
}

fn check_field_name(name: &str) -> Result<(), String> {
    let ok = name.chars().next().is_some_and(|c| c.is_ascii_lowercase())
        && name
            .chars()
            .all(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || c == '_')
        && !name.ends_with('_')
        && !name.contains("__");
    if ok {
        Ok(())
    } else {
        Err(format!(
            "field name `{name}` must be lower snake case: [a-z][a-z0-9_]*, no double or trailing `_`"
        ))
    }
}

fn check_constant_name(name: &str) -> Result<(), String> {
    let ok = name.chars().next().is_some_and(|c| c.is_ascii_uppercase())
        && name
            .chars()
            .all(|c| c.is_ascii_uppercase() || c.is_ascii_digit() || c == '_');
    if ok {
        Ok(())
    } else {
        Err(format!(
            "constant name `{name}` must be upper case: [A-Z][A-Z0-9_]*"
        ))
    }
}

fn parse_literal(text: &str, base: &BaseType) -> Result<Literal, String> {
    match base {
        BaseType::Primitive(Primitive::Bool) => match text {
            "true" | "True" | "1" => Ok(Literal::Bool(true)),
            "false" | "False" | "0" => Ok(Literal::Bool(false)),
            _ => Err(format!("`{text}` is not a bool value (true or false)")),
        },
        BaseType::Primitive(p @ (Primitive::Float32 | Primitive::Float64)) => text
            .parse::<f64>()
            .ok()
            .filter(|v| v.is_finite())
            .map(Literal::Float)
            .ok_or_else(|| format!("`{text}` is not a finite {} value", p.keyword())),
        BaseType::Primitive(p) => {
            let (lo, hi) = p.integer_range().expect("integer primitive");
            match text.parse::<i128>() {
                Ok(v) if (lo..=hi).contains(&v) => Ok(Literal::Int(v)),
                _ => Err(format!(
                    "`{text}` is not a {} value (range {lo}..={hi})",
                    p.keyword()
                )),
            }
        }
        BaseType::String { bound } => {
            let unquoted = match text.chars().next() {
                Some(q @ ('"' | '\'')) if text.len() >= 2 && text.ends_with(q) => {
                    &text[1..text.len() - 1]
                }
                _ => text,
            };
            if let Some(b) = bound
                && unquoted.len() > *b
            {
                return Err(format!(
                    "string value `{unquoted}` is longer than its bound {b}"
                ));
            }
            Ok(Literal::Str(unquoted.to_string()))
        }
        BaseType::Nested { .. } => Err("nested types take no literal value".into()),
    }
}

#[cfg(test)]
mod test;
