//! Setting a node up: command line → name, namespace and parameters; environment → DDS
//! participant; then the ros2-client node, its Spinner, rosout, diagnostics and `/clock`.

use std::time::Duration;

use metrocell_security::{SecurityEnvironment, SecuritySetting};
use ros2_client::{NodeName, NodeOptions};

use crate::background::{Background, BackgroundTasks, SimTime};
use crate::diagnostics::Diagnostics;
use crate::environment::DdsEnvironment;
use crate::error::{create_error, NodeError};
use crate::logging::Logger;
use crate::names::{fully_qualified_node_name, normalize_namespace, validate_node_name};
use crate::node::MetrocellNode;
use crate::params::{problem_error, ParamDecl, ParamSource, ParamValue, Parameters, USE_SIM_TIME};
use crate::ros_args::{parse_command_line, RosArgs};
use crate::shutdown::{trigger_on_signals, ShutdownToken};

/// Builder of a [`MetrocellNode`].
pub struct NodeBuilder {
    name: String,
    namespace: String,
    decls: Vec<ParamDecl>,
    /// The node's own arguments (flag, what it does), for `--help`.
    own_arguments: Vec<(String, String)>,
    ros_args: RosArgs,
    environment: Option<DdsEnvironment>,
    security: Option<SecurityEnvironment>,
    diagnostics_period: Option<Duration>,
    handle_signals: bool,
}

impl NodeBuilder {
    /// `default_name` is the node name unless `--ros-args -r __node:=...` renames it.
    pub fn new(default_name: &str) -> NodeBuilder {
        NodeBuilder {
            name: default_name.to_string(),
            namespace: "/".to_string(),
            decls: Vec::new(),
            own_arguments: Vec::new(),
            ros_args: RosArgs::default(),
            environment: None,
            security: None,
            diagnostics_period: Some(Duration::from_secs(1)),
            handle_signals: true,
        }
    }

    /// Default namespace (overridden by `-r __ns:=...`).
    pub fn namespace(mut self, ns: &str) -> NodeBuilder {
        self.namespace = ns.to_string();
        self
    }

    /// Document one of the node's own (non-ROS) arguments for `--help`, e.g.
    /// `("--bag IN_BAG [--output OUT_BAG]", "run on a recorded bag instead of DDS")`.
    pub fn node_argument(mut self, flag: &str, what: &str) -> NodeBuilder {
        self.own_arguments
            .push((flag.to_string(), what.to_string()));
        self
    }

    /// Parse a full argv (argv[0] first); returns the builder and the node's own arguments.
    /// `--help` or `-h` among the node's own arguments prints the help (parameters declared so
    /// far, so declare them first) and exits the process with status 0, before any DDS exists.
    pub fn args<I, S>(mut self, argv: I) -> Result<(NodeBuilder, Vec<String>), NodeError>
    where
        I: IntoIterator<Item = S>,
        S: Into<String>,
    {
        let cl = parse_command_line(argv)?;
        if crate::help::asks_for_help(cl.node_args.get(1..).unwrap_or_default()) {
            let program = cl
                .node_args
                .first()
                .map(|p| p.rsplit('/').next().unwrap_or(p).to_string())
                .unwrap_or_else(|| self.name.clone());
            print!(
                "{}",
                crate::help::help_text(&program, &self.name, &self.own_arguments, &self.decls)
            );
            std::process::exit(0);
        }
        self.ros_args = cl.ros;
        Ok((self, cl.node_args))
    }

    /// Use already parsed ROS arguments.
    pub fn ros_args(mut self, ros: RosArgs) -> NodeBuilder {
        self.ros_args = ros;
        self
    }

    pub fn param(mut self, decl: ParamDecl) -> NodeBuilder {
        self.decls.push(decl);
        self
    }

    pub fn params(mut self, decls: impl IntoIterator<Item = ParamDecl>) -> NodeBuilder {
        self.decls.extend(decls);
        self
    }

    /// Use this DDS environment instead of reading `ROS_DOMAIN_ID` etc. from the process.
    pub fn environment(mut self, env: DdsEnvironment) -> NodeBuilder {
        self.environment = Some(env);
        self
    }

    /// Use this security environment instead of reading `ROS_SECURITY_*` from the process (its
    /// `enclave_override` names the enclave, as `ROS_SECURITY_ENCLAVE_OVERRIDE` does).
    pub fn security(mut self, security: SecurityEnvironment) -> NodeBuilder {
        self.security = Some(security);
        self
    }

    /// Heartbeat period on `/diagnostics` (default 1 s); `None` disables it (e.g. for CLI tools).
    pub fn diagnostics_period(mut self, period: Option<Duration>) -> NodeBuilder {
        self.diagnostics_period = period;
        self
    }

    /// Whether SIGINT/SIGTERM trigger the node's shutdown token (default true).
    pub fn handle_signals(mut self, yes: bool) -> NodeBuilder {
        self.handle_signals = yes;
        self
    }

    /// Resolve name, namespace and parameters without opening DDS: for a node replaying a bag.
    pub fn build_offline(self) -> Result<crate::offline::OfflineNode, NodeError> {
        let (ros, id) = self.resolve_identity()?;
        let logger = Logger::stderr_only(&id.fqn, id.min_level);
        let shutdown = ShutdownToken::new();
        if self.handle_signals {
            trigger_on_signals(&shutdown).map_err(|e| create_error("SIGINT/SIGTERM handler", e))?;
        }
        Ok(crate::offline::OfflineNode {
            name: id.name,
            namespace: id.namespace,
            ros_args: ros,
            parameters: id.parameters,
            logger,
            shutdown,
        })
    }

    /// Name, namespace (remaps applied) and parameters, shared by live and offline nodes.
    /// Parameter warnings are printed here, before any DDS exists.
    fn resolve_identity(&self) -> Result<(RosArgs, Identity), NodeError> {
        let ros = self.ros_args.clone();
        let original = self.name.clone();
        let name = ros.node_name_remap(&original).unwrap_or(original.clone());
        validate_node_name(&name)?;
        let namespace = normalize_namespace(
            &ros.namespace_remap(&original)
                .unwrap_or(self.namespace.clone()),
        )?;
        let fqn = fully_qualified_node_name(&namespace, &name);
        let min_level = crate::logging::effective_log_level(&ros, &fqn);
        let parameters = Parameters::resolve(&self.decls, &ros, &fqn, &name)?;
        let early = Logger::stderr_only(&fqn, min_level);
        if let Some(w) = crate::dds_log::install_from_env() {
            early.warn(&w);
        }
        for w in parameters.warnings() {
            early.warn(w);
        }
        Ok((
            ros,
            Identity {
                name,
                namespace,
                fqn,
                min_level,
                parameters,
            },
        ))
    }

    pub fn build(self) -> Result<MetrocellNode, NodeError> {
        let (
            ros,
            Identity {
                name,
                namespace,
                fqn,
                min_level,
                parameters,
            },
        ) = self.resolve_identity()?;

        let env = match self.environment {
            Some(e) => e,
            None => DdsEnvironment::from_env()?,
        };
        let enclave_dir = match self
            .security
            .unwrap_or_else(SecurityEnvironment::from_env)
            .resolve(ros.enclave.as_deref())
            .map_err(|why| create_error(format!("node '{fqn}'"), why))?
        {
            SecuritySetting::Off => None,
            SecuritySetting::PermissiveFallback(why) => {
                Logger::stderr_only(&fqn, min_level).warn(&why);
                None
            }
            SecuritySetting::Enclave { enclave, dir } => {
                Logger::stderr_only(&fqn, min_level).info(format!(
                    "DDS Security on: enclave '{enclave}' ({})",
                    dir.display()
                ));
                crate::dds_log::install_security_events(&fqn);
                Some(dir)
            }
        };
        let context = crate::participant::create_context(&env, enclave_dir.as_deref())?;

        // The node reads `/clock` itself when it uses simulated time (`background`): the Spinner's
        // reader would be a second one in the participant (see `spinner_reads_clock`).
        let mut options = NodeOptions::new()
            .enable_rosout(!ros.disable_rosout)
            .spinner_reads_clock(false);
        for p in parameters.iter() {
            options = options.declare_parameter(&p.decl.name, p.value.to_ros());
        }
        let decls: Vec<ParamDecl> = parameters.iter().map(|p| p.decl.clone()).collect();
        options = options.parameter_validator(Box::new(
            move |pname: &str, value: &ros2_client::ParameterValue| {
                let Some(d) = decls.iter().find(|d| d.name == pname) else {
                    return Err(format!("parameter '{pname}' is not declared"));
                };
                let v = ParamValue::from_ros(value)
                    .ok_or_else(|| format!("parameter '{pname}': unsupported value type"))?;
                d.check(&v)
                    .map(|_| ())
                    .map_err(|p| problem_error(d, &v, ParamSource::Service, p).to_string())
            },
        ));

        let node_name = NodeName::new(&namespace, &name)
            .map_err(|e| create_error(format!("node '{fqn}'"), e))?;
        let mut ros_node = context
            .new_node(node_name, options)
            .map_err(|e| create_error(format!("node '{fqn}'"), e))?;
        let spinner = ros_node
            .spinner()
            .map_err(|e| create_error("ros2-client spinner", e))?;

        let logger = Logger::new(
            Some(ros_node.logging_handle()),
            &fqn,
            min_level,
            !ros.disable_stdout,
        );
        let diagnostics = Diagnostics::new(&fqn);
        let sim_time = SimTime::default();
        let use_sim_time = parameters.get::<bool>(USE_SIM_TIME).unwrap_or(false);

        let mut node = MetrocellNode::assemble(crate::node::Parts {
            name,
            namespace,
            ros_args: ros,
            parameters,
            context,
            ros_node,
            logger,
            diagnostics: diagnostics.clone(),
            sim_time: sim_time.clone(),
            use_sim_time,
            shutdown: ShutdownToken::new(),
        });
        if self.handle_signals {
            trigger_on_signals(&node.shutdown_token())
                .map_err(|e| create_error("SIGINT/SIGTERM handler", e))?;
        }

        let heartbeat = match self.diagnostics_period {
            Some(period) => {
                let publisher = node.publisher("/diagnostics", crate::qos::reliable())?;
                Some((publisher, diagnostics, period))
            }
            None => None,
        };
        let clock = if use_sim_time {
            // rclcpp's ClockQoS: best effort, keep last 1.
            let qos =
                crate::qos::sensor_data().history(ros2_client::qos::History::KeepLast { depth: 1 });
            let ros2_client_time = node.ros2_client_simulated_time();
            Some((
                node.subscription("/clock", qos)?,
                sim_time,
                ros2_client_time,
            ))
        } else {
            None
        };
        let background = Background::start(
            BackgroundTasks {
                spinner,
                heartbeat,
                clock,
            },
            &fqn,
        )
        .map_err(|e| create_error("node background thread", e))?;
        node.set_background(background);
        Ok(node)
    }
}

/// What `resolve_identity` settles before a node is built.
struct Identity {
    name: String,
    namespace: String,
    fqn: String,
    min_level: crate::ros_args::LogLevel,
    parameters: Parameters,
}
