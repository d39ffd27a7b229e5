//! Signed documents as DDS-Security wants them: the governance and permissions XML signed by the
//! permissions CA as S/MIME (PKCS#7, detached signature over the text, SHA-256), the form of
//! `openssl smime -sign -text` and of `ros2 security`.

use std::path::Path;

use openssl::pkcs7::{Pkcs7, Pkcs7Flags};
use openssl::stack::Stack;
use openssl::x509::store::X509StoreBuilder;
use openssl::x509::X509;

use crate::certificates::KeyAndCertificate;
use crate::error::{io_error, ssl_error, SecurityError};

/// The S/MIME document signing `content` with `signer`.
pub fn sign(content: &[u8], signer: &KeyAndCertificate) -> Result<Vec<u8>, SecurityError> {
    let flags = Pkcs7Flags::DETACHED | Pkcs7Flags::TEXT;
    let no_extra_certs = Stack::new().map_err(ssl_error("certificate stack"))?;
    let p7 = Pkcs7::sign(
        &signer.certificate,
        &signer.key,
        &no_extra_certs,
        content,
        flags,
    )
    .map_err(ssl_error("PKCS#7 signature"))?;
    p7.to_smime(content, flags).map_err(ssl_error("S/MIME"))
}

/// Sign the file `input` into `output`.
pub fn sign_file(
    input: &Path,
    output: &Path,
    signer: &KeyAndCertificate,
) -> Result<(), SecurityError> {
    let content = std::fs::read(input).map_err(io_error(input))?;
    let signed = sign(&content, signer)?;
    std::fs::write(output, signed).map_err(io_error(output))
}

/// The content of an S/MIME document if its signature verifies against `ca` (the check a DDS
/// participant makes on a governance or permissions document).
pub fn verify(smime: &[u8], ca: &X509) -> Result<Vec<u8>, String> {
    let (p7, content) = Pkcs7::from_smime(smime).map_err(|e| format!("not S/MIME: {e}"))?;
    let mut store = X509StoreBuilder::new().map_err(|e| e.to_string())?;
    store.add_cert(ca.clone()).map_err(|e| e.to_string())?;
    let store = store.build();
    let certs = Stack::new().map_err(|e| e.to_string())?;
    let mut out = Vec::new();
    p7.verify(
        &certs,
        &store,
        content.as_deref(),
        Some(&mut out),
        Pkcs7Flags::TEXT,
    )
    .map_err(|e| format!("signature does not verify: {e}"))?;
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::certificates::new_certificate_authority;

    #[test]
    fn a_signed_document_verifies_against_its_signer_only_and_not_once_altered() {
        let ca = new_certificate_authority("perm").unwrap();
        let other = new_certificate_authority("perm").unwrap();
        let doc = b"<dds><permissions/></dds>\n";
        let signed = sign(doc, &ca).unwrap();
        let text = String::from_utf8(signed.clone()).unwrap();
        assert!(text.contains("multipart/signed"), "{text}");
        assert!(
            text.contains("<dds><permissions/></dds>"),
            "clear text kept: {text}"
        );
        let back = verify(&signed, &ca.certificate).unwrap();
        assert_eq!(
            String::from_utf8(back).unwrap().trim_end(),
            "<dds><permissions/></dds>"
        );
        assert!(verify(&signed, &other.certificate).is_err());
        let altered = text.replacen("<permissions/>", "<permissionz/>", 1);
        assert!(verify(altered.as_bytes(), &ca.certificate).is_err());
    }
}
