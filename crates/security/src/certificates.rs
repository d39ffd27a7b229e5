//! X.509 certificates and keys as SROS2 makes them.
//!
//! DDS-Security §9.3.1 (the builtin authentication plugin, "DDS:Auth:PKI-DH") calls for ECDSA
//! over prime256v1 (NIST P-256) with SHA-256: every key here is a P-256 key, every certificate is
//! signed with ECDSA-SHA256, valid from now for ten years (as `ros2 security` does), private keys
//! are written unencrypted as PKCS#8 PEM (RustDDS cannot read password-protected identity keys),
//! certificates as PEM.

use std::path::Path;

use openssl::asn1::{Asn1Integer, Asn1Time};
use openssl::bn::{BigNum, MsbOption};
use openssl::ec::{EcGroup, EcKey};
use openssl::hash::MessageDigest;
use openssl::nid::Nid;
use openssl::pkey::{PKey, Private};
use openssl::x509::extension::BasicConstraints;
use openssl::x509::{X509Name, X509};

use crate::error::{io_error, ssl_error, SecurityError};

/// Days a certificate made here is valid for.
pub const VALIDITY_DAYS: u32 = 3650;

/// A key and its certificate.
pub struct KeyAndCertificate {
    pub key: PKey<Private>,
    pub certificate: X509,
}

/// A fresh P-256 key.
pub fn new_p256_key() -> Result<PKey<Private>, SecurityError> {
    let group =
        EcGroup::from_curve_name(Nid::X9_62_PRIME256V1).map_err(ssl_error("P-256 curve"))?;
    let ec = EcKey::generate(&group).map_err(ssl_error("P-256 key generation"))?;
    PKey::from_ec_key(ec).map_err(ssl_error("P-256 key"))
}

fn name_with_common_name(common_name: &str) -> Result<X509Name, SecurityError> {
    let mut b = X509Name::builder().map_err(ssl_error("X.509 name"))?;
    b.append_entry_by_nid(Nid::COMMONNAME, common_name)
        .map_err(ssl_error("X.509 common name"))?;
    Ok(b.build())
}

/// A self-signed certificate authority (basic constraints CA:TRUE, path length 1, critical).
pub fn new_certificate_authority(common_name: &str) -> Result<KeyAndCertificate, SecurityError> {
    let key = new_p256_key()?;
    let name = name_with_common_name(common_name)?;
    let certificate = build(&name, &name, &key, &key, true)?;
    Ok(KeyAndCertificate { key, certificate })
}

/// A participant's identity: a new key and a certificate with subject `CN=<common_name>` issued by
/// the CA (basic constraints CA:FALSE).
pub fn new_identity(
    common_name: &str,
    ca: &KeyAndCertificate,
) -> Result<KeyAndCertificate, SecurityError> {
    let key = new_p256_key()?;
    let subject = name_with_common_name(common_name)?;
    let certificate = build(
        &subject,
        ca.certificate.subject_name(),
        &key,
        &ca.key,
        false,
    )?;
    Ok(KeyAndCertificate { key, certificate })
}

fn build(
    subject: &openssl::x509::X509NameRef,
    issuer: &openssl::x509::X509NameRef,
    key: &PKey<Private>,
    signing_key: &PKey<Private>,
    ca: bool,
) -> Result<X509, SecurityError> {
    let e = ssl_error("X.509 certificate");
    let mut b = X509::builder().map_err(e)?;
    b.set_version(2).map_err(ssl_error("X.509 version"))?;
    let mut serial = BigNum::new().map_err(ssl_error("serial number"))?;
    serial
        .rand(127, MsbOption::MAYBE_ZERO, false)
        .map_err(ssl_error("serial number"))?;
    let serial = Asn1Integer::from_bn(&serial).map_err(ssl_error("serial number"))?;
    b.set_serial_number(&serial)
        .map_err(ssl_error("serial number"))?;
    b.set_subject_name(subject)
        .map_err(ssl_error("subject name"))?;
    b.set_issuer_name(issuer)
        .map_err(ssl_error("issuer name"))?;
    b.set_pubkey(key).map_err(ssl_error("public key"))?;
    let not_before = Asn1Time::days_from_now(0).map_err(ssl_error("validity"))?;
    let not_after = Asn1Time::days_from_now(VALIDITY_DAYS).map_err(ssl_error("validity"))?;
    b.set_not_before(&not_before)
        .map_err(ssl_error("validity"))?;
    b.set_not_after(&not_after).map_err(ssl_error("validity"))?;
    let constraints = if ca {
        BasicConstraints::new().critical().ca().pathlen(1).build()
    } else {
        BasicConstraints::new().build()
    }
    .map_err(ssl_error("basic constraints"))?;
    b.append_extension(constraints)
        .map_err(ssl_error("basic constraints"))?;
    b.sign(signing_key, MessageDigest::sha256())
        .map_err(ssl_error("certificate signature"))?;
    Ok(b.build())
}

/// Write the key (PKCS#8 PEM, unencrypted) and certificate (PEM).
pub fn write(
    pair: &KeyAndCertificate,
    key_path: &Path,
    cert_path: &Path,
) -> Result<(), SecurityError> {
    let key_pem = pair
        .key
        .private_key_to_pem_pkcs8()
        .map_err(ssl_error("private key PEM"))?;
    write_private(key_path, &key_pem)?;
    let cert_pem = pair
        .certificate
        .to_pem()
        .map_err(ssl_error("certificate PEM"))?;
    std::fs::write(cert_path, cert_pem).map_err(io_error(cert_path))
}

/// A private key file readable by its owner only.
fn write_private(path: &Path, bytes: &[u8]) -> Result<(), SecurityError> {
    use std::io::Write;
    use std::os::unix::fs::OpenOptionsExt;
    let mut f = std::fs::OpenOptions::new()
        .write(true)
        .create(true)
        .truncate(true)
        .mode(0o600)
        .open(path)
        .map_err(io_error(path))?;
    f.write_all(bytes).map_err(io_error(path))
}

/// Read a key and certificate written by [`write`] (or by `ros2 security`).
pub fn read(key_path: &Path, cert_path: &Path) -> Result<KeyAndCertificate, SecurityError> {
    let key_pem = std::fs::read(key_path).map_err(io_error(key_path))?;
    let key = PKey::private_key_from_pem(&key_pem).map_err(|e| SecurityError::Invalid {
        path: key_path.to_path_buf(),
        why: format!("not a PEM private key: {e}"),
    })?;
    let certificate = read_certificate(cert_path)?;
    Ok(KeyAndCertificate { key, certificate })
}

/// Read a PEM certificate.
pub fn read_certificate(cert_path: &Path) -> Result<X509, SecurityError> {
    let pem = std::fs::read(cert_path).map_err(io_error(cert_path))?;
    X509::from_pem(&pem).map_err(|e| SecurityError::Invalid {
        path: cert_path.to_path_buf(),
        why: format!("not a PEM X.509 certificate: {e}"),
    })
}

/// Whether `certificate` carries a valid signature of `ca`'s key and names `ca` as its issuer.
pub fn issued_by(certificate: &X509, ca: &X509) -> bool {
    let Ok(ca_key) = ca.public_key() else {
        return false;
    };
    certificate.verify(&ca_key).unwrap_or(false)
        && certificate.issuer_name_hash() == ca.subject_name_hash()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_identity_is_issued_by_its_ca_and_by_no_other() {
        let ca = new_certificate_authority("metrocellCA").unwrap();
        let rogue = new_certificate_authority("metrocellCA").unwrap();
        let id = new_identity("/cell/twin", &ca).unwrap();
        assert!(issued_by(&id.certificate, &ca.certificate));
        assert!(issued_by(&ca.certificate, &ca.certificate), "self-signed");
        // Same issuer name, other key: the signature must fail.
        assert!(!issued_by(&id.certificate, &rogue.certificate));
        let subject: Vec<String> = id
            .certificate
            .subject_name()
            .entries()
            .map(|e| String::from_utf8(e.data().as_slice().to_vec()).unwrap())
            .collect();
        assert_eq!(subject, vec!["/cell/twin".to_string()]);
    }

    #[test]
    fn keys_and_certificates_survive_a_round_trip_through_pem_files() {
        let dir = tempfile::tempdir().unwrap();
        let ca = new_certificate_authority("x").unwrap();
        let (k, c) = (dir.path().join("k.pem"), dir.path().join("c.pem"));
        write(&ca, &k, &c).unwrap();
        let back = read(&k, &c).unwrap();
        assert!(back.key.public_eq(&ca.key));
        assert_eq!(
            back.certificate.to_der().unwrap(),
            ca.certificate.to_der().unwrap()
        );
        use std::os::unix::fs::PermissionsExt;
        assert_eq!(
            std::fs::metadata(&k).unwrap().permissions().mode() & 0o777,
            0o600
        );
        assert!(std::fs::read_to_string(&k)
            .unwrap()
            .starts_with("-----BEGIN PRIVATE KEY-----"));
    }
}
