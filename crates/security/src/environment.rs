//! The ROS 2 security environment a node reads (rcl's rules, `rcl/security.c`):
//!
//! - `ROS_SECURITY_ENABLE=true` turns security on (any other value, or unset: off);
//! - `ROS_SECURITY_KEYSTORE` is the keystore's root;
//! - the node's enclave is `ROS_SECURITY_ENCLAVE_OVERRIDE` if set, else its `--ros-args --enclave`,
//!   else `/`; its files are in `KEYSTORE/enclaves/<enclave>`;
//! - `ROS_SECURITY_STRATEGY=Enforce`: a node whose enclave is missing or incomplete refuses to
//!   start; otherwise (`Permissive`, the default) it starts without security and says so.

use std::path::PathBuf;

use crate::keystore::{enclave_dir, ENCLAVE_FILES};

/// What the environment asks for.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct SecurityEnvironment {
    pub enabled: bool,
    pub enforce: bool,
    pub keystore: Option<PathBuf>,
    pub enclave_override: Option<String>,
}

/// How the participant is to be built.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum SecuritySetting {
    /// No security (not enabled).
    Off,
    /// Enabled but permissive and the enclave is unusable: run without security; the message says why.
    PermissiveFallback(String),
    /// DDS Security with the enclave's files.
    Enclave { enclave: String, dir: PathBuf },
}

impl SecurityEnvironment {
    /// Read through a lookup (the process environment in nodes; a map in tests).
    pub fn from_lookup(get: impl Fn(&str) -> Option<String>) -> SecurityEnvironment {
        let non_empty = |k: &str| get(k).filter(|v| !v.trim().is_empty());
        SecurityEnvironment {
            enabled: non_empty("ROS_SECURITY_ENABLE").as_deref() == Some("true"),
            enforce: non_empty("ROS_SECURITY_STRATEGY").as_deref() == Some("Enforce"),
            keystore: non_empty("ROS_SECURITY_KEYSTORE").map(PathBuf::from),
            enclave_override: non_empty("ROS_SECURITY_ENCLAVE_OVERRIDE"),
        }
    }

    pub fn from_env() -> SecurityEnvironment {
        SecurityEnvironment::from_lookup(|k| std::env::var(k).ok())
    }

    /// Decide, for a node whose `--enclave` argument is `enclave_arg`. `Err` (Enforce only) says
    /// what is missing and how to make it.
    pub fn resolve(&self, enclave_arg: Option<&str>) -> Result<SecuritySetting, String> {
        if !self.enabled {
            return Ok(SecuritySetting::Off);
        }
        let enclave = self
            .enclave_override
            .clone()
            .or_else(|| enclave_arg.map(str::to_string))
            .unwrap_or_else(|| "/".to_string());
        let problem = match &self.keystore {
            None => Some(
                "ROS_SECURITY_ENABLE=true but ROS_SECURITY_KEYSTORE is not set: set it to a \
                 keystore made with `metrocell security create-keystore`"
                    .to_string(),
            ),
            Some(ks) => {
                let dir = enclave_dir(ks, &enclave);
                let missing: Vec<&str> = ENCLAVE_FILES
                    .iter()
                    .copied()
                    .filter(|f| !dir.join(f).is_file())
                    .collect();
                if missing.is_empty() {
                    return Ok(SecuritySetting::Enclave { enclave, dir });
                }
                Some(format!(
                    "enclave '{enclave}' in keystore {} is missing {} in {}: make it with \
                     `metrocell security create-enclave {} {enclave}`",
                    ks.display(),
                    missing.join(", "),
                    dir.display(),
                    ks.display()
                ))
            }
        };
        let why = problem.unwrap_or_default();
        if self.enforce {
            Err(format!(
                "SECURITY ERROR (ROS_SECURITY_STRATEGY=Enforce): {why}"
            ))
        } else {
            Ok(SecuritySetting::PermissiveFallback(format!(
                "security is enabled but {why}; running WITHOUT security because \
                 ROS_SECURITY_STRATEGY is not Enforce"
            )))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn env(pairs: &[(&str, &str)]) -> SecurityEnvironment {
        let pairs: Vec<(String, String)> = pairs
            .iter()
            .map(|(k, v)| (k.to_string(), v.to_string()))
            .collect();
        SecurityEnvironment::from_lookup(|k| {
            pairs.iter().find(|(a, _)| a == k).map(|(_, v)| v.clone())
        })
    }

    #[test]
    fn rcl_rules() {
        let dir = tempfile::tempdir().unwrap();
        let ks = dir.path().join("ks");
        crate::keystore::create_keystore(&ks, 0).unwrap();
        crate::keystore::create_enclave(&ks, "/cell/twin").unwrap();
        let ks_s = ks.to_str().unwrap();

        assert_eq!(
            env(&[]).resolve(Some("/cell/twin")).unwrap(),
            SecuritySetting::Off
        );
        assert_eq!(
            env(&[("ROS_SECURITY_ENABLE", "1")]).resolve(None).unwrap(),
            SecuritySetting::Off,
            "only the word true enables, as in rcl"
        );
        let on = env(&[
            ("ROS_SECURITY_ENABLE", "true"),
            ("ROS_SECURITY_KEYSTORE", ks_s),
        ]);
        assert_eq!(
            on.resolve(Some("/cell/twin")).unwrap(),
            SecuritySetting::Enclave {
                enclave: "/cell/twin".into(),
                dir: ks.join("enclaves/cell/twin")
            }
        );
        // No such enclave: permissive falls back with the reason, Enforce refuses.
        match on.resolve(Some("/cell/ghost")).unwrap() {
            SecuritySetting::PermissiveFallback(m) => {
                assert!(
                    m.contains("'/cell/ghost'") && m.contains("WITHOUT security"),
                    "{m}"
                )
            }
            other => panic!("{other:?}"),
        }
        let enforce = SecurityEnvironment {
            enforce: true,
            ..on.clone()
        };
        let e = enforce.resolve(Some("/cell/ghost")).unwrap_err();
        assert!(e.contains("Enforce") && e.contains("create-enclave"), "{e}");
        let e = enforce.resolve(None).unwrap_err();
        assert!(e.contains("enclave '/'"), "{e}");
        // The override wins over the argument.
        let over = SecurityEnvironment {
            enclave_override: Some("/cell/twin".into()),
            ..enforce.clone()
        };
        assert!(matches!(
            over.resolve(Some("/cell/ghost")),
            Ok(SecuritySetting::Enclave { .. })
        ));
        let no_ks = env(&[
            ("ROS_SECURITY_ENABLE", "true"),
            ("ROS_SECURITY_STRATEGY", "Enforce"),
        ]);
        assert!(no_ks
            .resolve(None)
            .unwrap_err()
            .contains("ROS_SECURITY_KEYSTORE is not set"));
    }
}
