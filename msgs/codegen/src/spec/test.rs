use super::*;

fn parse(text: &str) -> MessageSpec {
    parse_message(TypeName::msg("pkg", "T"), text).expect("parses")
}

fn parse_err(text: &str) -> String {
    parse_message(TypeName::msg("pkg", "T"), text)
        .unwrap_err()
        .to_string()
}

#[test]
fn fields_arrays_and_bounds() {
    let m = parse(
        "# A type.\n\nfloat64[] a\nfloat32[3] b\nstring<=10 c\nint8[<=4] d\nOther e\ngeometry_msgs/Pose f\n",
    );
    assert_eq!(m.doc, vec!["A type."]);
    let kinds: Vec<_> = m
        .fields
        .iter()
        .map(|f| (f.name.as_str(), f.ty.array))
        .collect();
    assert_eq!(
        kinds,
        vec![
            ("a", ArrayKind::Unbounded),
            ("b", ArrayKind::Fixed(3)),
            ("c", ArrayKind::Single),
            ("d", ArrayKind::Bounded(4)),
            ("e", ArrayKind::Single),
            ("f", ArrayKind::Single),
        ]
    );
    assert_eq!(m.fields[2].ty.base, BaseType::String { bound: Some(10) });
    match &m.fields[4].ty.base {
        BaseType::Nested { name, written } => {
            assert_eq!(name.to_string(), "pkg/msg/Other");
            assert_eq!(written, "pkg/Other");
        }
        other => panic!("{other:?}"),
    }
}

#[test]
fn constants_defaults_and_comments() {
    let m = parse(
        "uint8 MODE_A=1  # first\nstring NAME=\"a # b\"\nfloat64 w 1 # unit: none\n# about x\nbool x true\n",
    );
    assert_eq!(m.constants[0].value, Literal::Int(1));
    assert_eq!(m.constants[0].doc, vec!["first"]);
    assert_eq!(m.constants[1].value, Literal::Str("a # b".into()));
    assert_eq!(m.fields[0].default, Some(Literal::Float(1.0)));
    assert_eq!(m.fields[0].doc, vec!["unit: none"]);
    assert_eq!(m.fields[1].doc, vec!["about x"]);
    assert_eq!(m.fields[1].default, Some(Literal::Bool(true)));
}

#[test]
fn errors_name_the_problem() {
    assert!(
        parse_err("uint8 x 300\n").contains("range 0..=255"),
        "{}",
        parse_err("uint8 x 300\n")
    );
    assert!(parse_err("wstring x\n").contains("wide strings"));
    assert!(parse_err("Header h\n").contains("std_msgs/Header"));
    assert!(parse_err("float64 BadName\n").contains("lower snake case"));
    assert!(parse_err("float64 x\nint8 x\n").contains("defined twice"));
    assert!(parse_err("float64[0] x\n").contains("positive integer"));
    assert!(parse_err("float64[] x [1, 2]\n").contains("not supported"));
    assert!(parse_err("int32 lower=1\n").contains("upper case"));
    assert!(parse_err("float64\n").contains("no field name"));
    assert!(parse_err("float64 a\n  bad-type b\n").starts_with("pkg/msg/T:2:"));
}

#[test]
fn service_halves() {
    let s = parse_service(
        TypeName::new("pkg", "srv", "Do"),
        "int32 a\n---\nbool ok\nstring why\n",
    )
    .unwrap();
    assert_eq!(s.request.name.to_string(), "pkg/srv/Do_Request");
    assert_eq!(s.response.name.to_string(), "pkg/srv/Do_Response");
    assert_eq!(s.request.text, "int32 a\n");
    assert_eq!(s.response.fields.len(), 2);
    let err = parse_service(TypeName::new("pkg", "srv", "Do"), "int32 a\n").unwrap_err();
    assert!(err.message.contains("exactly 1 `---`"));
}

#[test]
fn action_parts() {
    let a = parse_action(
        TypeName::new("pkg", "action", "Move"),
        "float64 target\n---\nint32 code\n---\nfloat64 error\nfloat64 time\n",
    )
    .unwrap();
    assert_eq!(a.goal.name.to_string(), "pkg/action/Move_Goal");
    assert_eq!(a.result.name.to_string(), "pkg/action/Move_Result");
    assert_eq!(a.feedback.name.to_string(), "pkg/action/Move_Feedback");
    assert_eq!(a.feedback.fields.len(), 2);
    assert_eq!(a.result.text, "int32 code\n");
    let err = parse_action(TypeName::new("pkg", "action", "Move"), "a\n---\nb\n").unwrap_err();
    assert!(err.message.contains("exactly 2 `---`"), "{err}");
    // Errors in later parts name their line in the whole file.
    let err = parse_action(
        TypeName::new("pkg", "action", "Move"),
        "float64 a\n---\nint32 b\n---\nbad-type c\n",
    )
    .unwrap_err();
    assert_eq!(err.line, 5, "{err}");
}

#[test]
fn dds_names() {
    assert_eq!(
        TypeName::msg("sensor_msgs", "JointState").dds_name(),
        "sensor_msgs::msg::dds_::JointState_"
    );
    assert_eq!(
        TypeName::new("composuite_msgs", "srv", "Reset_Request").dds_name(),
        "composuite_msgs::srv::dds_::Reset_Request_"
    );
}
