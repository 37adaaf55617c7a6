//! All interface types known to one build, indexed by full name.

use std::collections::BTreeMap;
use std::fmt;
use std::path::{Path, PathBuf};

use crate::spec::{
    self, ActionSpec, ArrayKind, BaseType, Field, FieldType, MessageSpec, ParseError, ServiceSpec,
    TypeName,
};

/// Why loading interface files failed.
#[derive(Debug)]
pub enum LoadError {
    /// A file could not be read.
    Io(PathBuf, std::io::Error),
    /// A file did not parse.
    Parse(ParseError),
    /// A field names a type no loaded package defines.
    Unresolved {
        /// The referring type.
        from: String,
        /// The field.
        field: String,
        /// The missing type.
        missing: String,
    },
    /// The same type was loaded twice.
    Duplicate(String),
}

impl fmt::Display for LoadError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            LoadError::Io(path, e) => write!(f, "{}: {e}", path.display()),
            LoadError::Parse(e) => write!(f, "{e}"),
            LoadError::Unresolved {
                from,
                field,
                missing,
            } => write!(
                f,
                "{from}: field `{field}` has type {missing}, which no loaded package defines \
                 (add its .msg file under msgs/standard/<package>/msg/)"
            ),
            LoadError::Duplicate(name) => write!(f, "{name} is defined twice"),
        }
    }
}

impl std::error::Error for LoadError {}

/// Every message (including the request/response halves of services) and service of a build.
#[derive(Debug, Default, Clone)]
pub struct Registry {
    /// Messages by full name; service halves appear as `pkg/srv/Name_Request` / `_Response`.
    pub messages: BTreeMap<TypeName, MessageSpec>,
    /// Services by full name.
    pub services: BTreeMap<TypeName, ServiceSpec>,
    /// Actions by full name; their parts appear as messages `pkg/action/Name_Goal`, `_Result`,
    /// `_Feedback` (the wrappers around them on the wire come from ros2-client).
    pub actions: BTreeMap<TypeName, ActionSpec>,
}

impl Registry {
    /// Load every `msg/*.msg`, `srv/*.srv` and `action/*.action` under `dir` as package
    /// `package`. Returns the files read, sorted, so a build script can watch them.
    pub fn load_package(&mut self, package: &str, dir: &Path) -> Result<Vec<PathBuf>, LoadError> {
        let mut read = Vec::new();
        for kind in ["msg", "srv", "action"] {
            for path in sorted_files(&dir.join(kind), kind)? {
                let text =
                    std::fs::read_to_string(&path).map_err(|e| LoadError::Io(path.clone(), e))?;
                let stem = path
                    .file_stem()
                    .and_then(|s| s.to_str())
                    .unwrap_or_default()
                    .to_string();
                let name = TypeName::new(package, kind, &stem);
                let located = |e: ParseError| {
                    LoadError::Parse(ParseError {
                        file: path.display().to_string(),
                        ..e
                    })
                };
                match kind {
                    "msg" => {
                        self.insert_message(spec::parse_message(name, &text).map_err(located)?)?
                    }
                    "srv" => {
                        self.insert_service(spec::parse_service(name, &text).map_err(located)?)?
                    }
                    _ => self.insert_action(spec::parse_action(name, &text).map_err(located)?)?,
                }
                read.push(path);
            }
        }
        Ok(read)
    }

    /// Add one parsed message.
    pub fn insert_message(&mut self, msg: MessageSpec) -> Result<(), LoadError> {
        if self.messages.contains_key(&msg.name) {
            return Err(LoadError::Duplicate(msg.name.to_string()));
        }
        self.messages.insert(msg.name.clone(), msg);
        Ok(())
    }

    /// Add one parsed service, its two halves, and its event message as messages.
    pub fn insert_service(&mut self, srv: ServiceSpec) -> Result<(), LoadError> {
        if self.services.contains_key(&srv.name) {
            return Err(LoadError::Duplicate(srv.name.to_string()));
        }
        self.insert_message(srv.request.clone())?;
        self.insert_message(srv.response.clone())?;
        self.insert_message(event_message(&srv))?;
        self.services.insert(srv.name.clone(), srv);
        Ok(())
    }

    /// Add one parsed action and its goal, result and feedback as messages.
    pub fn insert_action(&mut self, action: ActionSpec) -> Result<(), LoadError> {
        if self.actions.contains_key(&action.name) {
            return Err(LoadError::Duplicate(action.name.to_string()));
        }
        self.insert_message(action.goal.clone())?;
        self.insert_message(action.result.clone())?;
        self.insert_message(action.feedback.clone())?;
        self.actions.insert(action.name.clone(), action);
        Ok(())
    }

    /// Check that every nested field type resolves to a loaded message.
    pub fn check_references(&self) -> Result<(), LoadError> {
        for msg in self.messages.values() {
            for field in &msg.fields {
                if let BaseType::Nested { name, .. } = &field.ty.base
                    && !self.messages.contains_key(name)
                {
                    return Err(LoadError::Unresolved {
                        from: msg.name.to_string(),
                        field: field.name.clone(),
                        missing: name.to_string(),
                    });
                }
            }
        }
        Ok(())
    }

    /// A message by name; panics if absent (call [`Registry::check_references`] first).
    pub fn message(&self, name: &TypeName) -> &MessageSpec {
        self.messages
            .get(name)
            .unwrap_or_else(|| panic!("{name} not loaded"))
    }

    /// The packages present, sorted.
    pub fn packages(&self) -> Vec<String> {
        let mut packages: Vec<String> = self.messages.keys().map(|n| n.package.clone()).collect();
        packages.dedup();
        packages
    }
}

/// `pkg/srv/Name_Event`, the message ROS 2 (since Iron) publishes on a service's
/// `_service_event` topic and covers in the service's type hash: the event info plus at most one
/// request and at most one response.
fn event_message(srv: &ServiceSpec) -> MessageSpec {
    let nested = |name: &TypeName| BaseType::Nested {
        name: name.clone(),
        written: format!("{}/{}", name.package, name.name),
    };
    let field = |name: &str, base: BaseType, array: ArrayKind| Field {
        name: name.into(),
        ty: FieldType { base, array },
        default: None,
        doc: Vec::new(),
    };
    let info = TypeName::msg("service_msgs", "ServiceEventInfo");
    let fields = vec![
        field("info", nested(&info), ArrayKind::Single),
        field("request", nested(&srv.request.name), ArrayKind::Bounded(1)),
        field(
            "response",
            nested(&srv.response.name),
            ArrayKind::Bounded(1),
        ),
    ];
    let text = format!(
        "service_msgs/ServiceEventInfo info\n{0}/{1}_Request[<=1] request\n{0}/{1}_Response[<=1] response\n",
        srv.name.package, srv.name.name
    );
    MessageSpec {
        name: TypeName::new(
            &srv.name.package,
            "srv",
            &format!("{}_Event", srv.name.name),
        ),
        fields,
        constants: Vec::new(),
        text,
        doc: vec![format!(
            "Event of the service `{}` (introspection).",
            srv.name
        )],
    }
}

fn sorted_files(dir: &Path, extension: &str) -> Result<Vec<PathBuf>, LoadError> {
    if !dir.is_dir() {
        return Ok(Vec::new());
    }
    let entries = std::fs::read_dir(dir).map_err(|e| LoadError::Io(dir.to_path_buf(), e))?;
    let mut files: Vec<PathBuf> = entries
        .filter_map(|entry| entry.ok().map(|e| e.path()))
        .filter(|p| p.extension().and_then(|e| e.to_str()) == Some(extension))
        .collect();
    files.sort();
    Ok(files)
}
