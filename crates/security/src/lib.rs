//! DDS Security for metrocell's nodes, the SROS2 way.
//!
//! Nodes run with the builtin plugins of DDS-Security 1.1 as RustDDS implements them
//! (authentication "DDS:Auth:PKI-DH", access control "DDS:Access:Permissions", cryptography
//! "DDS:Crypto:AES-GCM-GMAC"): each participant proves its identity with a certificate from the
//! keystore's identity CA, presents a permissions document signed by its permissions CA, and
//! the domain's governance (also signed) says what is protected. This crate makes keystores in
//! the layout `ros2 security` uses ([`keystore`]), translates SROS2 policies into permissions
//! ([`policy`]) and reads the `ROS_SECURITY_*` environment a node starts with ([`environment`]).

pub mod certificates;
pub mod environment;
mod error;
pub mod keystore;
pub mod policy;
pub mod smime;

pub use environment::{SecurityEnvironment, SecuritySetting};
pub use error::SecurityError;
