//! `metrocell security`: SROS2 keystores for DDS Security, as `ros2 security` makes them.

use std::path::PathBuf;

use metrocell_security::keystore;

const AFTER_HELP: &str = "\
How a cell runs secured (the ROS 2 environment, as with any ROS 2 node):
  metrocell security create-keystore keystore
  metrocell security create-enclave keystore /cell/twin          # one per node, or shared
  metrocell security create-permission keystore /cell/tracker tracker_policy.xml   # narrow one
  export ROS_SECURITY_KEYSTORE=$PWD/keystore ROS_SECURITY_ENABLE=true ROS_SECURITY_STRATEGY=Enforce
  metrocell launch cell.yaml            # each node's `enclave: /cell/twin` (or ros_args: --enclave /cell/twin)

What protects what: the governance (keystore/enclaves/governance.xml, signed) admits no
unauthenticated participant and encrypts discovery, liveliness and every message; each enclave's
identity (cert.pem, CN=<enclave>) is issued by the keystore's CA, and its permissions
(permissions.xml, signed) say which topics it may publish and subscribe — everything for a new
enclave, what a policy grants after create-permission, everything else denied. A participant
without a certificate from this CA, or with one altered, is not authenticated and sees nothing;
one whose permissions do not name a topic can neither read nor write it.

With ROS_SECURITY_STRATEGY=Enforce a node whose enclave is missing refuses to start; otherwise it
starts unsecured and warns. The files are those of `ros2 security` (a keystore made by either
works with the other's nodes). METROCELL_DDS_LOG=warn shows RustDDS's own account of a refused
participant.";

#[derive(clap::Subcommand)]
#[command(after_help = AFTER_HELP)]
pub enum SecurityCommand {
    /// Make a keystore: a CA (P-256, ten years) and the domain's governance signed by it
    CreateKeystore {
        /// Directory of the keystore (made if absent; existing files are kept)
        keystore: PathBuf,
        /// The ROS domain the governance and permissions are for (default: ROS_DOMAIN_ID, else 0)
        #[arg(long)]
        domain_id: Option<u16>,
    },
    /// Make an enclave: an identity issued by the keystore's CA and permissions allowing every topic
    CreateEnclave {
        keystore: PathBuf,
        /// The enclave's name, an absolute ROS namespace such as /cell/twin
        enclave: String,
    },
    /// Replace an enclave's permissions by what an sros2 policy file grants it
    CreatePermission {
        keystore: PathBuf,
        enclave: String,
        /// An sros2 policy (<policy><enclaves><enclave path=…><profiles><profile ns= node=><topics publish="ALLOW"…>)
        policy: PathBuf,
    },
    /// List a keystore's enclaves
    ListEnclaves { keystore: PathBuf },
}

/// ROS_DOMAIN_ID as every node reads it (0 when unset).
fn default_domain() -> Result<u16, String> {
    metrocell_node::DdsEnvironment::from_env()
        .map(|e| e.domain_id)
        .map_err(|e| format!("{e}; or give --domain-id"))
}

fn run_inner(command: SecurityCommand) -> Result<(), String> {
    let e = |e: metrocell_security::SecurityError| e.to_string();
    match command {
        SecurityCommand::CreateKeystore {
            keystore: ks,
            domain_id,
        } => {
            let domain = match domain_id {
                Some(d) => d,
                None => default_domain()?,
            };
            keystore::create_keystore(&ks, domain).map_err(e)?;
            println!(
                "keystore {} (CA {}, governance for ROS domain {domain})",
                ks.display(),
                keystore::CA_COMMON_NAME
            );
        }
        SecurityCommand::CreateEnclave {
            keystore: ks,
            enclave,
        } => {
            let dir = keystore::create_enclave(&ks, &enclave).map_err(e)?;
            println!(
                "enclave {enclave}: {} (permissions: every topic)",
                dir.display()
            );
        }
        SecurityCommand::CreatePermission {
            keystore: ks,
            enclave,
            policy,
        } => {
            let dir = keystore::create_permission(&ks, &enclave, &policy).map_err(e)?;
            println!(
                "enclave {enclave}: permissions from {} in {}",
                policy.display(),
                dir.join("permissions.xml").display()
            );
        }
        SecurityCommand::ListEnclaves { keystore: ks } => {
            for enclave in keystore::list_enclaves(&ks).map_err(e)? {
                println!("{enclave}");
            }
        }
    }
    Ok(())
}

pub fn run(command: SecurityCommand) -> i32 {
    match run_inner(command) {
        Ok(()) => 0,
        Err(m) => {
            eprintln!("metrocell security: {m}");
            1
        }
    }
}
