//! The keystore: the layout `ros2 security` writes and rmw reads, so that a keystore made here
//! works with ROS 2's tools and the other way round.
//!
//! ```text
//! <keystore>/public/ca.cert.pem               the CA (one CA plays both roles, as in sros2)
//! <keystore>/public/identity_ca.cert.pem      -> ca.cert.pem
//! <keystore>/public/permissions_ca.cert.pem   -> ca.cert.pem
//! <keystore>/private/ca.key.pem               (and identity_ca.key.pem, permissions_ca.key.pem -> it)
//! <keystore>/enclaves/governance.xml, governance.p7s   (signed by the permissions CA)
//! <keystore>/enclaves/<enclave>/cert.pem, key.pem     the enclave's identity, CN=<enclave>
//!                   permissions.xml, permissions.p7s
//!                   identity_ca.cert.pem, permissions_ca.cert.pem, governance.p7s -> the above
//! ```

use std::path::{Path, PathBuf};

use crate::certificates::{self, KeyAndCertificate};
use crate::error::{io_error, SecurityError};
use crate::policy::{self, EnclaveGrant};
use crate::smime;

/// The common name of the CA a new keystore gets.
pub const CA_COMMON_NAME: &str = "metrocellCA";

/// The files a participant's enclave directory must hold (rmw_dds_common's names).
pub const ENCLAVE_FILES: [&str; 6] = [
    "identity_ca.cert.pem",
    "cert.pem",
    "key.pem",
    "permissions_ca.cert.pem",
    "governance.p7s",
    "permissions.p7s",
];

/// The directory of an enclave in a keystore (`/cell/twin` → `KEYSTORE/enclaves/cell/twin`).
pub fn enclave_dir(keystore: &Path, enclave: &str) -> PathBuf {
    let rel = enclave.trim_start_matches('/');
    let base = keystore.join("enclaves");
    if rel.is_empty() {
        base
    } else {
        base.join(rel)
    }
}

/// Whether `keystore` has the CA files and the signed governance a keystore needs.
pub fn is_keystore(keystore: &Path) -> bool {
    [
        "public/permissions_ca.cert.pem",
        "public/identity_ca.cert.pem",
        "private/permissions_ca.key.pem",
        "private/identity_ca.key.pem",
        "enclaves/governance.p7s",
    ]
    .iter()
    .all(|f| keystore.join(f).is_file())
}

fn require_keystore(keystore: &Path) -> Result<(), SecurityError> {
    if is_keystore(keystore) {
        Ok(())
    } else {
        Err(SecurityError::Invalid {
            path: keystore.to_path_buf(),
            why: "not a keystore (no CA or no signed governance): make one with \
                  `metrocell security create-keystore`"
                .into(),
        })
    }
}

/// The governance document of a domain: sros2's defaults — no unauthenticated participant, join
/// access control, discovery, liveliness and every message encrypted, every topic read- and
/// write-controlled.
pub fn governance_document(domain_id: u16) -> String {
    format!(
        r#"<?xml version="1.0" encoding="UTF-8"?>
<dds xmlns:xsi="http://www.w3.org/2001/XMLSchema-instance" xsi:noNamespaceSchemaLocation="http://www.omg.org/spec/DDS-SECURITY/20170901/omg_shared_ca_governance.xsd">
  <domain_access_rules>
    <domain_rule>
      <domains>
        <id>{domain_id}</id>
      </domains>
      <allow_unauthenticated_participants>false</allow_unauthenticated_participants>
      <enable_join_access_control>true</enable_join_access_control>
      <discovery_protection_kind>ENCRYPT</discovery_protection_kind>
      <liveliness_protection_kind>ENCRYPT</liveliness_protection_kind>
      <rtps_protection_kind>ENCRYPT</rtps_protection_kind>
      <topic_access_rules>
        <topic_rule>
          <topic_expression>*</topic_expression>
          <enable_discovery_protection>true</enable_discovery_protection>
          <enable_liveliness_protection>true</enable_liveliness_protection>
          <enable_read_access_control>true</enable_read_access_control>
          <enable_write_access_control>true</enable_write_access_control>
          <metadata_protection_kind>ENCRYPT</metadata_protection_kind>
          <data_protection_kind>ENCRYPT</data_protection_kind>
        </topic_rule>
      </topic_access_rules>
    </domain_rule>
  </domain_access_rules>
</dds>
"#
    )
}

fn mkdir(p: &Path) -> Result<(), SecurityError> {
    std::fs::create_dir_all(p).map_err(io_error(p))
}

/// A relative symlink `dst` → `target` (replacing what is there).
fn link(target: &Path, dst: &Path) -> Result<(), SecurityError> {
    let parent = dst.parent().unwrap_or(Path::new("."));
    let rel = relative(parent, target);
    if dst.symlink_metadata().is_ok() {
        std::fs::remove_file(dst).map_err(io_error(dst))?;
    }
    std::os::unix::fs::symlink(&rel, dst).map_err(io_error(dst))
}

/// `target` relative to the directory `from` (both under the same keystore).
fn relative(from: &Path, target: &Path) -> PathBuf {
    let f: Vec<_> = from.components().collect();
    let t: Vec<_> = target.components().collect();
    let common = f.iter().zip(&t).take_while(|(a, b)| a == b).count();
    let mut out = PathBuf::new();
    for _ in common..f.len() {
        out.push("..");
    }
    for c in &t[common..] {
        out.push(c);
    }
    out
}

/// Make a keystore: a new CA (unless one is there), the governance of `domain_id` signed by it.
/// Files already present are kept, as `ros2 security create_keystore` does.
pub fn create_keystore(keystore: &Path, domain_id: u16) -> Result<(), SecurityError> {
    for d in ["public", "private", "enclaves"] {
        mkdir(&keystore.join(d))?;
    }
    let ca_cert = keystore.join("public/ca.cert.pem");
    let ca_key = keystore.join("private/ca.key.pem");
    let have_ca = [
        "public/permissions_ca.cert.pem",
        "public/identity_ca.cert.pem",
        "private/permissions_ca.key.pem",
        "private/identity_ca.key.pem",
    ]
    .iter()
    .all(|f| keystore.join(f).is_file());
    if !have_ca {
        let ca = certificates::new_certificate_authority(CA_COMMON_NAME)?;
        certificates::write(&ca, &ca_key, &ca_cert)?;
        for role in ["identity_ca", "permissions_ca"] {
            link(&ca_cert, &keystore.join(format!("public/{role}.cert.pem")))?;
            link(&ca_key, &keystore.join(format!("private/{role}.key.pem")))?;
        }
    }
    let gov = keystore.join("enclaves/governance.xml");
    if !gov.is_file() {
        std::fs::write(&gov, governance_document(domain_id)).map_err(io_error(&gov))?;
    }
    let signed = keystore.join("enclaves/governance.p7s");
    if !signed.is_file() {
        smime::sign_file(&gov, &signed, &permissions_ca(keystore)?)?;
    }
    Ok(())
}

fn identity_ca(keystore: &Path) -> Result<KeyAndCertificate, SecurityError> {
    certificates::read(
        &keystore.join("private/identity_ca.key.pem"),
        &keystore.join("public/identity_ca.cert.pem"),
    )
}

fn permissions_ca(keystore: &Path) -> Result<KeyAndCertificate, SecurityError> {
    certificates::read(
        &keystore.join("private/permissions_ca.key.pem"),
        &keystore.join("public/permissions_ca.cert.pem"),
    )
}

/// The governance's domain id (what a new permissions document is written for).
fn governance_domain(keystore: &Path) -> Result<u16, SecurityError> {
    let gov = keystore.join("enclaves/governance.xml");
    let text = std::fs::read_to_string(&gov).map_err(io_error(&gov))?;
    let invalid = |why: String| SecurityError::Invalid {
        path: gov.clone(),
        why,
    };
    let doc = roxmltree::Document::parse(&text).map_err(|e| invalid(format!("not XML: {e}")))?;
    let id = doc
        .descendants()
        .find(|n| n.has_tag_name("id") && n.ancestors().any(|a| a.has_tag_name("domains")))
        .and_then(|n| n.text())
        .ok_or_else(|| invalid("no <domains><id> in the governance".into()))?;
    id.trim()
        .parse()
        .map_err(|_| invalid(format!("domain id '{id}' is not a number")))
}

/// Make an enclave: its identity (unless it has one), links to the CA certificates and the
/// governance, and permissions that allow everything (sros2's default policy) — narrow them with
/// [`create_permission`].
pub fn create_enclave(keystore: &Path, enclave: &str) -> Result<PathBuf, SecurityError> {
    require_keystore(keystore)?;
    policy::validate_enclave_name(enclave).map_err(SecurityError::Usage)?;
    let dir = enclave_dir(keystore, enclave);
    mkdir(&dir)?;
    for f in ["identity_ca.cert.pem", "permissions_ca.cert.pem"] {
        link(&keystore.join("public").join(f), &dir.join(f))?;
    }
    link(
        &keystore.join("enclaves/governance.p7s"),
        &dir.join("governance.p7s"),
    )?;
    let (cert, key) = (dir.join("cert.pem"), dir.join("key.pem"));
    if !cert.is_file() || !key.is_file() {
        let id = certificates::new_identity(enclave, &identity_ca(keystore)?)?;
        certificates::write(&id, &key, &cert)?;
    }
    let mut grant = policy::parse_policy(policy::DEFAULT_POLICY)
        .map_err(SecurityError::Usage)?
        .remove(0);
    grant.enclave = enclave.to_string();
    write_permissions(keystore, &dir, &grant)?;
    Ok(dir)
}

/// Replace an enclave's permissions by what `policy_file` grants it.
pub fn create_permission(
    keystore: &Path,
    enclave: &str,
    policy_file: &Path,
) -> Result<PathBuf, SecurityError> {
    require_keystore(keystore)?;
    let dir = enclave_dir(keystore, enclave);
    if !dir.join("cert.pem").is_file() {
        return Err(SecurityError::Invalid {
            path: dir,
            why: format!(
                "enclave '{enclave}' has no identity: make it first with \
                 `metrocell security create-enclave {} {enclave}`",
                keystore.display()
            ),
        });
    }
    let grants = policy::read_policy(policy_file)?;
    let names: Vec<&str> = grants.iter().map(|g| g.enclave.as_str()).collect();
    let grant = grants
        .iter()
        .find(|g| g.enclave == enclave)
        .ok_or_else(|| SecurityError::Invalid {
            path: policy_file.to_path_buf(),
            why: format!("the policy has no enclave '{enclave}' (it has {names:?})"),
        })?;
    write_permissions(keystore, &dir, grant)?;
    Ok(dir)
}

fn write_permissions(
    keystore: &Path,
    dir: &Path,
    grant: &EnclaveGrant,
) -> Result<(), SecurityError> {
    let domain = governance_domain(keystore)?;
    let now = chrono::Utc::now();
    let fmt = "%Y-%m-%dT%H:%M:%S";
    // A minute of slack before now: participants on hosts whose clocks lag a little still accept it.
    let not_before = (now - chrono::Duration::minutes(1)).format(fmt).to_string();
    let not_after = (now + chrono::Duration::days(i64::from(certificates::VALIDITY_DAYS)))
        .format(fmt)
        .to_string();
    let xml = policy::permissions_document(grant, domain, &not_before, &not_after);
    let path = dir.join("permissions.xml");
    std::fs::write(&path, xml).map_err(io_error(&path))?;
    smime::sign_file(
        &path,
        &dir.join("permissions.p7s"),
        &permissions_ca(keystore)?,
    )
}

/// The enclaves of a keystore (directories under `enclaves/` with a `key.pem`), sorted.
pub fn list_enclaves(keystore: &Path) -> Result<Vec<String>, SecurityError> {
    require_keystore(keystore)?;
    let base = keystore.join("enclaves");
    let mut out = Vec::new();
    let mut stack = vec![base.clone()];
    while let Some(d) = stack.pop() {
        for entry in std::fs::read_dir(&d).map_err(io_error(&d))? {
            let p = entry.map_err(io_error(&d))?.path();
            if p.is_dir() && !p.is_symlink() {
                if p.join("key.pem").is_file() {
                    let rel = p.strip_prefix(&base).unwrap_or(&p);
                    out.push(format!("/{}", rel.display()));
                }
                stack.push(p);
            }
        }
    }
    out.sort();
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_keystore_and_an_enclave_have_the_sros2_layout_and_verify() {
        let dir = tempfile::tempdir().unwrap();
        let ks = dir.path().join("keystore");
        create_keystore(&ks, 42).unwrap();
        assert!(is_keystore(&ks));
        let e = create_enclave(&ks, "/cell/twin").unwrap();
        assert_eq!(e, ks.join("enclaves/cell/twin"));
        for f in ENCLAVE_FILES {
            assert!(e.join(f).is_file(), "{f}");
        }
        assert!(std::fs::read_link(e.join("governance.p7s"))
            .unwrap()
            .is_relative());
        let ca = certificates::read_certificate(&e.join("identity_ca.cert.pem")).unwrap();
        let id = certificates::read_certificate(&e.join("cert.pem")).unwrap();
        assert!(certificates::issued_by(&id, &ca));
        let perm = smime::verify(&std::fs::read(e.join("permissions.p7s")).unwrap(), &ca).unwrap();
        let perm = String::from_utf8(perm).unwrap();
        assert!(
            perm.contains("<subject_name>CN=/cell/twin</subject_name>"),
            "{perm}"
        );
        assert!(perm.contains("<id>42</id>"));
        let gov = smime::verify(&std::fs::read(e.join("governance.p7s")).unwrap(), &ca).unwrap();
        assert!(String::from_utf8(gov).unwrap().contains("<id>42</id>"));
        assert_eq!(list_enclaves(&ks).unwrap(), vec!["/cell/twin".to_string()]);

        // Keeping what is there: a second create_keystore neither replaces the CA nor the identity.
        let ca_before = std::fs::read(ks.join("public/ca.cert.pem")).unwrap();
        let id_before = std::fs::read(e.join("cert.pem")).unwrap();
        create_keystore(&ks, 42).unwrap();
        create_enclave(&ks, "/cell/twin").unwrap();
        assert_eq!(
            std::fs::read(ks.join("public/ca.cert.pem")).unwrap(),
            ca_before
        );
        assert_eq!(std::fs::read(e.join("cert.pem")).unwrap(), id_before);
    }

    #[test]
    fn a_permission_narrows_an_enclave_to_its_policy() {
        let dir = tempfile::tempdir().unwrap();
        let ks = dir.path().join("ks");
        create_keystore(&ks, 0).unwrap();
        create_enclave(&ks, "/outsider").unwrap();
        let policy = dir.path().join("policy.xml");
        std::fs::write(
            &policy,
            r#"<policy version="0.2.0"><enclaves><enclave path="/outsider"><profiles>
               <profile ns="/" node="outsider"><topics publish="ALLOW" subscribe="ALLOW"><topic>other</topic></topics></profile>
               </profiles></enclave></enclaves></policy>"#,
        )
        .unwrap();
        let e = create_permission(&ks, "/outsider", &policy).unwrap();
        let xml = std::fs::read_to_string(e.join("permissions.xml")).unwrap();
        assert!(
            xml.contains("<topic>rt/other</topic>") && !xml.contains("rt/*"),
            "{xml}"
        );

        let err = create_permission(&ks, "/nobody", &policy)
            .unwrap_err()
            .to_string();
        assert!(err.contains("create-enclave"), "{err}");
        create_enclave(&ks, "/nobody").unwrap();
        let err = create_permission(&ks, "/nobody", &policy)
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("has no enclave '/nobody'") && err.contains("/outsider"),
            "{err}"
        );
        let err = create_enclave(&dir.path().join("none"), "/x")
            .unwrap_err()
            .to_string();
        assert!(err.contains("create-keystore"), "{err}");
    }
}
