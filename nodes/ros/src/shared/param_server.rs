//! A node's parameters and the six `rcl_interfaces` parameter services (`ros2 param
//! list/get/set/describe` talk to them), served on a thread of their own in the node's service
//! wire format.
//!
//! ros2-client can serve these from its spinner, but only in the Fast DDS format, and its
//! spinner also subscribes to `/clock` as `builtin_interfaces/msg/Time` (a type no ROS node
//! publishes there), which would show up in every `ros2 topic list -t`. So the suite keeps its
//! parameters here and runs no spinner.

use std::collections::BTreeMap;
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;

use futures::{FutureExt, StreamExt};
use ros2_client::dds::{Node, Server, ServiceMapping};
use ros2_client::parameters::raw;
use ros2_client::rcl_interfaces::{
    DescribeParametersRequest, DescribeParametersResponse, GetParameterTypesRequest,
    GetParameterTypesResponse, GetParametersRequest, GetParametersResponse, ListParametersRequest,
    ListParametersResponse, ListParametersResult, SetParametersAtomicallyResponse,
    SetParametersRequest, SetParametersResponse,
};
use ros2_client::{Message, Name, Parameter, ParameterValue, ServiceTypeName};

use crate::shared::params::ParamSpec;

/// The built-in parameter every ROS node has; ours are the clock, so it stays false.
pub const USE_SIM_TIME: &str = "use_sim_time";

/// A parameter changed through the services (already checked).
#[derive(Debug, Clone)]
pub struct ParamChange {
    /// Its name.
    pub name: String,
    /// The new value.
    pub value: ParameterValue,
}

/// The node's parameter values, checked against their declarations on every change.
pub struct Parameters {
    specs: Vec<ParamSpec>,
    values: Mutex<BTreeMap<String, ParameterValue>>,
    changes: async_channel::Sender<ParamChange>,
}

impl Parameters {
    /// The store with its starting values; changes are sent to `changes`.
    pub fn new(
        specs: &[ParamSpec],
        values: Vec<(String, ParameterValue)>,
        changes: async_channel::Sender<ParamChange>,
    ) -> Parameters {
        let mut map: BTreeMap<String, ParameterValue> = values.into_iter().collect();
        map.insert(USE_SIM_TIME.into(), ParameterValue::Boolean(false));
        Parameters {
            specs: specs.to_vec(),
            values: Mutex::new(map),
            changes,
        }
    }

    /// The value of `name` (`NotSet` for an unknown name, as rcl answers).
    pub fn get(&self, name: &str) -> ParameterValue {
        self.values
            .lock()
            .expect("no panics while holding the lock")
            .get(name)
            .cloned()
            .unwrap_or(ParameterValue::NotSet)
    }

    /// All names, sorted.
    pub fn names(&self) -> Vec<String> {
        self.values
            .lock()
            .expect("no panics while holding the lock")
            .keys()
            .cloned()
            .collect()
    }

    /// Check `value` for `name`; the value in its declared type.
    pub fn check(&self, name: &str, value: ParameterValue) -> Result<ParameterValue, String> {
        if name == USE_SIM_TIME {
            return match value {
                ParameterValue::Boolean(false) => Ok(value),
                _ => Err("use_sim_time must stay false: this suite is the clock".into()),
            };
        }
        match self.specs.iter().find(|s| s.name == name) {
            Some(spec) => spec.accept(value),
            None => Err(format!(
                "`{name}` is not a parameter of this node; its parameters are: {}",
                self.specs
                    .iter()
                    .map(|s| s.name)
                    .collect::<Vec<_>>()
                    .join(", ")
            )),
        }
    }

    /// Set one parameter after checking it.
    pub fn set(&self, name: &str, value: ParameterValue) -> Result<(), String> {
        let value = self.check(name, value)?;
        self.values
            .lock()
            .expect("no panics while holding the lock")
            .insert(name.into(), value.clone());
        // A closed channel only means the node is shutting down.
        let _ = self.changes.try_send(ParamChange {
            name: name.into(),
            value,
        });
        Ok(())
    }

    /// Set all or none.
    pub fn set_all(&self, params: Vec<Parameter>) -> Result<(), String> {
        let checked = params
            .into_iter()
            .map(|p| self.check(&p.name, p.value).map(|v| (p.name, v)))
            .collect::<Result<Vec<_>, _>>()?;
        for (name, value) in checked {
            self.set(&name, value)?;
        }
        Ok(())
    }

    fn describe(&self, name: &str) -> raw::ParameterDescriptor {
        let spec = self.specs.iter().find(|s| s.name == name);
        raw::ParameterDescriptor {
            name: name.into(),
            r#type: ParameterValue::to_parameter_type_raw(&self.get(name)),
            description: match (spec, name) {
                (Some(s), _) => s.description.into(),
                (None, USE_SIM_TIME) => "always false: the sim publishes the clock".into(),
                _ => String::new(),
            },
            additional_constraints: String::new(),
            read_only: name == USE_SIM_TIME,
            dynamic_typing: false,
            floating_point_range: Vec::new(),
            integer_range: Vec::new(),
        }
    }
}

struct Servers {
    get: Server<GetParametersRequest, GetParametersResponse>,
    get_types: Server<GetParameterTypesRequest, GetParameterTypesResponse>,
    set: Server<SetParametersRequest, SetParametersResponse>,
    set_atomically: Server<SetParametersRequest, SetParametersAtomicallyResponse>,
    list: Server<ListParametersRequest, ListParametersResponse>,
    describe: Server<DescribeParametersRequest, DescribeParametersResponse>,
}

fn server<Req, Resp>(
    node: &mut Node,
    mapping: ServiceMapping,
    fully_qualified: &str,
    service: &str,
    type_name: &str,
) -> Result<Server<Req, Resp>, String>
where
    Req: Message + Clone + 'static,
    Resp: Message + 'static,
{
    let name = Name::parse(&format!("{fully_qualified}/{service}"))
        .map_err(|e| format!("parameter service {service}: {e:?}"))?;
    let qos = crate::shared::qos::parameter_services();
    node.create_server(
        mapping,
        &name,
        &ServiceTypeName::new("rcl_interfaces", type_name),
        qos.clone(),
        qos,
    )
    .map_err(|e| format!("parameter service {service}: {e:?}"))
}

/// The running parameter services; dropping it stops them.
pub struct ParameterServices {
    stop: async_channel::Sender<()>,
    thread: Option<JoinHandle<()>>,
}

impl ParameterServices {
    /// Create the six services of `node` and serve them on a thread.
    pub fn start(
        node: &mut Node,
        mapping: ServiceMapping,
        params: Arc<Parameters>,
    ) -> Result<ParameterServices, String> {
        let fq = node.fully_qualified_name();
        let servers = Servers {
            get: server(node, mapping, &fq, "get_parameters", "GetParameters")?,
            get_types: server(
                node,
                mapping,
                &fq,
                "get_parameter_types",
                "GetParameterTypes",
            )?,
            set: server(node, mapping, &fq, "set_parameters", "SetParameters")?,
            set_atomically: server(
                node,
                mapping,
                &fq,
                "set_parameters_atomically",
                "SetParametersAtomically",
            )?,
            list: server(node, mapping, &fq, "list_parameters", "ListParameters")?,
            describe: server(
                node,
                mapping,
                &fq,
                "describe_parameters",
                "DescribeParameters",
            )?,
        };
        let (stop, stopped) = async_channel::bounded(1);
        let thread = std::thread::Builder::new()
            .name("parameters".into())
            .spawn(move || smol::block_on(serve(servers, params, stopped)))
            .map_err(|e| format!("cannot start the parameter thread: {e}"))?;
        Ok(ParameterServices {
            stop,
            thread: Some(thread),
        })
    }
}

impl Drop for ParameterServices {
    fn drop(&mut self) {
        let _ = self.stop.try_send(());
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

fn result(r: Result<(), String>) -> raw::SetParametersResult {
    match r {
        Ok(()) => raw::SetParametersResult {
            successful: true,
            reason: String::new(),
        },
        Err(reason) => raw::SetParametersResult {
            successful: false,
            reason,
        },
    }
}

async fn serve(s: Servers, params: Arc<Parameters>, stopped: async_channel::Receiver<()>) {
    let mut get = std::pin::pin!(s.get.receive_request_stream());
    let mut get_types = std::pin::pin!(s.get_types.receive_request_stream());
    let mut set = std::pin::pin!(s.set.receive_request_stream());
    let mut set_atomically = std::pin::pin!(s.set_atomically.receive_request_stream());
    let mut list = std::pin::pin!(s.list.receive_request_stream());
    let mut describe = std::pin::pin!(s.describe.receive_request_stream());
    // A request that cannot be decoded or answered is dropped; the client's deadline handles it.
    loop {
        futures::select! {
            _ = stopped.recv().fuse() => return,
            r = get.select_next_some() => if let Ok((id, req)) = r {
                let values = req.names.iter().map(|n| raw::ParameterValue::from(params.get(n))).collect();
                let _ = s.get.send_response(id, GetParametersResponse { values });
            },
            r = get_types.select_next_some() => if let Ok((id, req)) = r {
                let values = req.names.iter().map(|n| ParameterValue::to_parameter_type_raw(&params.get(n))).collect();
                let _ = s.get_types.send_response(id, GetParameterTypesResponse { values });
            },
            r = set.select_next_some() => if let Ok((id, req)) = r {
                let results = req.parameter.into_iter().map(Parameter::from)
                    .map(|p| result(params.set(&p.name, p.value))).collect();
                let _ = s.set.send_response(id, SetParametersResponse { results });
            },
            r = set_atomically.select_next_some() => if let Ok((id, req)) = r {
                let all = req.parameter.into_iter().map(Parameter::from).collect();
                let _ = s.set_atomically.send_response(id, SetParametersAtomicallyResponse { result: result(params.set_all(all)) });
            },
            r = list.select_next_some() => if let Ok((id, req)) = r {
                let names = params.names().into_iter()
                    .filter(|n| req.prefixes.is_empty() || req.prefixes.iter().any(|p| n == p || n.starts_with(&format!("{p}."))))
                    .collect();
                let _ = s.list.send_response(id, ListParametersResponse { result: ListParametersResult { names, prefixes: Vec::new() } });
            },
            r = describe.select_next_some() => if let Ok((id, req)) = r {
                let values = req.names.iter().map(|n| params.describe(n)).collect();
                let _ = s.describe.send_response(id, DescribeParametersResponse { values });
            },
        }
    }
}
