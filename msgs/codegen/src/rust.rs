//! Emits the Rust source of every loaded type.
//!
//! Each message becomes a plain struct whose field order is the CDR order, deriving serde so the
//! CDR serializer used by `ros2-client` (`cdr-encoding`) writes exactly the ROS 2 layout. Each
//! also implements `RosMessage` with its ROS and DDS names, `ros2msg` definition text, RIHS01
//! hash, a static field description and a bounds check. The support types named here
//! (`RosMessage`, `TypeDescription`, ...) live in the hand-written part of `composuite_msgs`.

use std::fmt::Write as _;

use crate::spec::{ArrayKind, BaseType, Field, Literal, MessageSpec, Primitive, TypeName};
use crate::{Registry, definition, type_hash};

/// Rust keywords that ROS field names might use; emitted as raw identifiers.
const KEYWORDS: &[&str] = &[
    "as", "async", "await", "box", "break", "const", "continue", "crate", "dyn", "else", "enum",
    "extern", "false", "fn", "for", "gen", "if", "impl", "in", "let", "loop", "match", "mod",
    "move", "mut", "pub", "ref", "return", "static", "struct", "super", "trait", "true", "type",
    "unsafe", "use", "where", "while", "yield",
];

/// The Rust struct name of a type: `Reset_Request` becomes `ResetRequest`.
pub fn rust_type_name(name: &TypeName) -> String {
    name.name.replace('_', "")
}

/// The Rust path of a type from the crate root.
pub fn rust_path(name: &TypeName) -> String {
    format!(
        "crate::{}::{}::{}",
        name.package,
        name.kind,
        rust_type_name(name)
    )
}

fn field_ident(name: &str) -> String {
    if KEYWORDS.contains(&name) {
        format!("r#{name}")
    } else {
        name.to_string()
    }
}

fn element_rust_type(base: &BaseType) -> String {
    match base {
        BaseType::Primitive(p) => p.rust_type().to_string(),
        BaseType::String { .. } => "::std::string::String".to_string(),
        BaseType::Nested { name, .. } => rust_path(name),
    }
}

fn field_rust_type(field: &Field) -> String {
    let element = element_rust_type(&field.ty.base);
    match field.ty.array {
        ArrayKind::Single => element,
        ArrayKind::Fixed(n) => format!("[{element}; {n}]"),
        ArrayKind::Bounded(_) | ArrayKind::Unbounded => format!("::std::vec::Vec<{element}>"),
    }
}

fn literal_rust(value: &Literal, base: &BaseType) -> String {
    match (value, base) {
        (Literal::Bool(b), _) => b.to_string(),
        (Literal::Int(v), BaseType::Primitive(p)) if p.integer_range().is_some() => {
            format!("{v}_{}", p.rust_type())
        }
        (Literal::Int(v), BaseType::Primitive(p)) => format!("{v}.0_{}", p.rust_type()),
        (Literal::Float(v), BaseType::Primitive(p)) => format!("{v:?}_{}", p.rust_type()),
        (Literal::Str(s), _) => format!("{s:?}"),
        (other, _) => panic!("literal {other:?} does not fit {base:?}"),
    }
}

fn constant_rust_type(base: &BaseType) -> String {
    match base {
        BaseType::Primitive(p) => p.rust_type().to_string(),
        _ => "&'static str".to_string(),
    }
}

fn doc_attrs(out: &mut String, indent: &str, lines: &[String]) {
    for line in lines {
        let line = plain_text(line);
        writeln!(out, "{indent}#[doc = {:?}]", format!(" {line}")).unwrap();
    }
}

/// A `.msg` comment line as rustdoc Markdown that shows it as written: outside `code spans`,
/// brackets and angle brackets are escaped, so `[0, 1]` is not a link, `"<joint>/<interface>"`
/// not an HTML tag and a leading `> 0 closes` not a block quote.
fn plain_text(line: &str) -> String {
    let mut out = String::with_capacity(line.len());
    for (i, part) in line.split('`').enumerate() {
        if i > 0 {
            out.push('`');
        }
        if i % 2 == 1 {
            out.push_str(part);
            continue;
        }
        for c in part.chars() {
            match c {
                '[' => out.push_str("\\["),
                ']' => out.push_str("\\]"),
                '<' => out.push_str("&lt;"),
                '>' => out.push_str("&gt;"),
                _ => out.push(c),
            }
        }
    }
    out
}

fn element_description(base: &BaseType) -> String {
    match base {
        BaseType::Primitive(p) => format!("crate::ElementType::{:?}", p),
        BaseType::String { bound } => format!("crate::ElementType::String {{ bound: {bound:?} }}"),
        BaseType::Nested { name, .. } => {
            format!(
                "crate::ElementType::Nested(<{} as crate::RosMessage>::DESCRIPTION)",
                rust_path(name)
            )
        }
    }
}

fn array_description(array: ArrayKind) -> String {
    format!("crate::ArrayKind::{array:?}")
}

/// The fields as emitted: ROS gives an empty structure one placeholder octet.
fn emitted_fields(msg: &MessageSpec) -> Vec<Field> {
    if msg.fields.is_empty() {
        vec![Field {
            name: "structure_needs_at_least_one_member".into(),
            ty: crate::spec::FieldType {
                base: BaseType::Primitive(Primitive::UInt8),
                array: ArrayKind::Single,
            },
            default: None,
            doc: vec!["Placeholder: ROS 2 gives every empty structure one octet.".into()],
        }]
    } else {
        msg.fields.clone()
    }
}

fn emit_bounds_check(out: &mut String, fields: &[Field]) {
    out.push_str("    fn check_bounds(&self) -> ::std::result::Result<(), crate::BoundsError> {\n");
    for field in fields {
        let ident = field_ident(&field.name);
        let name = &field.name;
        let is_sequence = matches!(
            field.ty.array,
            ArrayKind::Bounded(_) | ArrayKind::Unbounded | ArrayKind::Fixed(_)
        );
        if let ArrayKind::Bounded(n) = field.ty.array {
            writeln!(
                out,
                "        crate::BoundsError::check({name:?}, self.{ident}.len(), {n})?;"
            )
            .unwrap();
        }
        let element_check = match &field.ty.base {
            BaseType::String { bound: Some(b) } => Some(format!(
                "crate::BoundsError::check(\"\", element.len(), {b})"
            )),
            BaseType::Nested { .. } => Some("crate::RosMessage::check_bounds(element)".to_string()),
            _ => None,
        };
        if let Some(check) = element_check {
            if is_sequence {
                writeln!(
                    out,
                    "        for (index, element) in self.{ident}.iter().enumerate() {{\n            \
                     {check}.map_err(|e| e.within(&::std::format!(\"{name}[{{index}}]\")))?;\n        }}"
                )
                .unwrap();
            } else {
                writeln!(
                    out,
                    "        {{\n            let element = &self.{ident};\n            \
                     {check}.map_err(|e| e.within({name:?}))?;\n        }}"
                )
                .unwrap();
            }
        }
    }
    out.push_str("        Ok(())\n    }\n");
}

fn emit_message(out: &mut String, registry: &Registry, msg: &MessageSpec) {
    let rust_name = rust_type_name(&msg.name);
    let fields = emitted_fields(msg);
    let mut doc = vec![format!("`{}`", msg.name)];
    if !msg.doc.is_empty() {
        doc.push(String::new());
        doc.extend(msg.doc.iter().cloned());
    }
    doc_attrs(out, "", &doc);
    out.push_str("#[derive(Debug, Clone, PartialEq, ::serde::Serialize, ::serde::Deserialize)]\n");
    writeln!(out, "pub struct {rust_name} {{").unwrap();
    for field in &fields {
        let mut field_doc = vec![format!("`{}`", field_type_text(field))];
        field_doc.extend(field.doc.iter().cloned());
        doc_attrs(out, "    ", &field_doc);
        if matches!(field.ty.array, ArrayKind::Fixed(_)) {
            out.push_str("    #[serde(with = \"crate::cdr::fixed_array\")]\n");
        }
        writeln!(
            out,
            "    pub {}: {},",
            field_ident(&field.name),
            field_rust_type(field)
        )
        .unwrap();
    }
    out.push_str("}\n\n");

    writeln!(out, "impl ::std::default::Default for {rust_name} {{").unwrap();
    out.push_str("    fn default() -> Self {\n        Self {\n");
    for field in &fields {
        let value = match (&field.default, field.ty.array) {
            (Some(literal), _) => match literal {
                Literal::Str(_) => format!(
                    "::std::string::String::from({})",
                    literal_rust(literal, &field.ty.base)
                ),
                _ => literal_rust(literal, &field.ty.base),
            },
            (None, ArrayKind::Fixed(_)) => {
                "::std::array::from_fn(|_| ::std::default::Default::default())".into()
            }
            (None, _) => "::std::default::Default::default()".into(),
        };
        writeln!(out, "            {}: {value},", field_ident(&field.name)).unwrap();
    }
    out.push_str("        }\n    }\n}\n\n");

    if !msg.constants.is_empty() {
        writeln!(out, "impl {rust_name} {{").unwrap();
        for constant in &msg.constants {
            let mut doc = vec![format!("Constant `{}` of `{}`.", constant.name, msg.name)];
            doc.extend(constant.doc.iter().cloned());
            doc_attrs(out, "    ", &doc);
            writeln!(
                out,
                "    pub const {}: {} = {};",
                constant.name,
                constant_rust_type(&constant.ty),
                literal_rust(&constant.value, &constant.ty)
            )
            .unwrap();
        }
        out.push_str("}\n\n");
    }

    writeln!(
        out,
        "#[cfg(feature = \"ros2-client\")]\nimpl ::ros2_client::Message for {rust_name} {{}}\n"
    )
    .unwrap();
    writeln!(out, "impl crate::RosMessage for {rust_name} {{").unwrap();
    writeln!(
        out,
        "    const ROS_NAME: &'static str = {:?};",
        msg.name.to_string()
    )
    .unwrap();
    writeln!(
        out,
        "    const DDS_NAME: &'static str = {:?};",
        msg.name.dds_name()
    )
    .unwrap();
    writeln!(
        out,
        "    const DEFINITION: &'static str = {:?};",
        definition::full_text(registry, &msg.name)
    )
    .unwrap();
    writeln!(
        out,
        "    const TYPE_HASH: &'static str = {:?};",
        type_hash::rihs01(registry, &msg.name)
    )
    .unwrap();
    writeln!(
        out,
        "    const DESCRIPTION: &'static crate::TypeDescription = &crate::TypeDescription {{\n        \
         ros_name: {:?},\n        fields: &[",
        msg.name.to_string()
    )
    .unwrap();
    for field in &fields {
        writeln!(
            out,
            "            crate::FieldDescription {{ name: {:?}, element: {}, array: {} }},",
            field.name,
            element_description(&field.ty.base),
            array_description(field.ty.array)
        )
        .unwrap();
    }
    out.push_str("        ],\n    };\n");
    emit_bounds_check(out, &fields);
    out.push_str("}\n\n");
}

/// The type as written in a `.msg` file (for docs).
fn field_type_text(field: &Field) -> String {
    let base = match &field.ty.base {
        BaseType::Primitive(p) => p.keyword().to_string(),
        BaseType::String { bound: None } => "string".into(),
        BaseType::String { bound: Some(b) } => format!("string<={b}"),
        BaseType::Nested { written, .. } => written.clone(),
    };
    let suffix = match field.ty.array {
        ArrayKind::Single => String::new(),
        ArrayKind::Fixed(n) => format!("[{n}]"),
        ArrayKind::Bounded(n) => format!("[<={n}]"),
        ArrayKind::Unbounded => "[]".into(),
    };
    format!("{base}{suffix} {}", field.name)
}

/// Rust source for every type in the registry, to be `include!`d at the crate root.
pub fn generate(registry: &Registry) -> String {
    let mut out = String::from(
        "// Generated by composuite_msgs_codegen from the .msg/.srv/.action files. Do not edit.\n\n",
    );
    for package in registry.packages() {
        writeln!(
            out,
            "/// Types of the ROS package `{package}`.\n#[allow(clippy::derivable_impls)] // generated: one uniform shape for every type\npub mod {package} {{"
        )
        .unwrap();
        for kind in ["msg", "srv", "action"] {
            let messages: Vec<&MessageSpec> = registry
                .messages
                .values()
                .filter(|m| m.name.package == package && m.name.kind == kind)
                .collect();
            if messages.is_empty() {
                continue;
            }
            let what = match kind {
                "msg" => "Messages",
                "srv" => "Services and their request/response messages",
                _ => "The goal, result and feedback messages of actions",
            };
            writeln!(out, "/// {what} of `{package}`.\npub mod {kind} {{").unwrap();
            for msg in messages {
                emit_message(&mut out, registry, msg);
            }
            for service in registry
                .services
                .values()
                .filter(|s| s.name.package == package && s.name.kind == kind)
            {
                let rust_name = rust_type_name(&service.name);
                writeln!(out, "/// The service `{}`.", service.name).unwrap();
                out.push_str("#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]\n");
                writeln!(out, "pub struct {rust_name};\n").unwrap();
                writeln!(out, "impl crate::RosService for {rust_name} {{").unwrap();
                writeln!(
                    out,
                    "    type Request = {};",
                    rust_path(&service.request.name)
                )
                .unwrap();
                writeln!(
                    out,
                    "    type Response = {};",
                    rust_path(&service.response.name)
                )
                .unwrap();
                writeln!(
                    out,
                    "    const ROS_NAME: &'static str = {:?};",
                    service.name.to_string()
                )
                .unwrap();
                writeln!(
                    out,
                    "    const TYPE_HASH: &'static str = {:?};",
                    type_hash::rihs01(registry, &service.name)
                )
                .unwrap();
                out.push_str("}\n\n");
            }
            out.push_str("}\n");
        }
        out.push_str("}\n\n");
    }

    out.push_str(
        "/// Calls `visitor.visit::<T>()` for every message type of this crate, in name order.\n",
    );
    out.push_str("pub fn visit_messages<V: crate::MessageVisitor>(visitor: &mut V) {\n");
    for msg in registry.messages.values() {
        writeln!(out, "    visitor.visit::<{}>();", rust_path(&msg.name)).unwrap();
    }
    out.push_str("}\n\n");
    out.push_str(
        "/// Calls `visitor.visit::<S>()` for every service type of this crate, in name order.\n",
    );
    out.push_str("pub fn visit_services<V: crate::ServiceVisitor>(visitor: &mut V) {\n");
    for service in registry.services.values() {
        writeln!(out, "    visitor.visit::<{}>();", rust_path(&service.name)).unwrap();
    }
    out.push_str("}\n");
    out
}

#[cfg(test)]
mod tests {
    use super::plain_text;

    #[test]
    fn comments_are_shown_as_written() {
        assert_eq!(plain_text("in [0, 1]"), "in \\[0, 1\\]");
        assert_eq!(
            plain_text("\"<joint>/<interface>\""),
            "\"&lt;joint&gt;/&lt;interface&gt;\""
        );
        assert_eq!(plain_text("> 0 closes"), "&gt; 0 closes");
        assert_eq!(plain_text("`a[i] <b>` and [c]"), "`a[i] <b>` and \\[c\\]");
        assert_eq!(plain_text("plain"), "plain");
    }
}
