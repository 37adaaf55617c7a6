//! The keystore's cryptography, with OpenSSL (what RustDDS's and Fast DDS's security plugins
//! read it with): EC P-256 keys, X.509 v3 certificates signed with ECDSA-SHA256, and S/MIME
//! signatures of the governance and permissions documents (PKCS#7, detached, text mode —
//! the Content-Type Fast DDS expects).

use openssl::asn1::{Asn1Integer, Asn1Time};
use openssl::bn::{BigNum, MsbOption};
use openssl::ec::{EcGroup, EcKey};
use openssl::error::ErrorStack;
use openssl::hash::MessageDigest;
use openssl::nid::Nid;
use openssl::pkcs7::{Pkcs7, Pkcs7Flags};
use openssl::pkey::{PKey, Private};
use openssl::stack::Stack;
use openssl::x509::extension::BasicConstraints;
use openssl::x509::{X509, X509Name, X509NameRef};

/// When a certificate starts and stops being valid (seconds since the Unix epoch).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Validity {
    /// The first second it is valid.
    pub not_before: i64,
    /// The last.
    pub not_after: i64,
}

impl Validity {
    /// From a day before `now` for `days` days, as `ros2 security` makes them (a day's slack
    /// for clocks that lag the one that signed).
    pub fn from_day_before(now: i64, days: i64) -> Validity {
        let not_before = now - 86_400;
        Validity {
            not_before,
            not_after: not_before + days * 86_400,
        }
    }
}

/// A certificate authority: its key and self-signed certificate.
pub struct Authority {
    /// The private key.
    pub key: PKey<Private>,
    /// The certificate.
    pub cert: X509,
}

/// A new EC P-256 private key.
pub fn new_key() -> Result<PKey<Private>, ErrorStack> {
    let group = EcGroup::from_curve_name(Nid::X9_62_PRIME256V1)?;
    PKey::from_ec_key(EcKey::generate(&group)?)
}

/// The key as unencrypted PKCS#8 PEM (what the security plugins read: no passwords).
pub fn key_pem(key: &PKey<Private>) -> Result<Vec<u8>, ErrorStack> {
    key.private_key_to_pem_pkcs8()
}

/// A name with one common name (CN).
fn common_name(cn: &str) -> Result<X509Name, ErrorStack> {
    let mut name = X509Name::builder()?;
    name.append_entry_by_nid(Nid::COMMONNAME, cn)?;
    Ok(name.build())
}

/// A random positive serial number of 159 bits (RFC 5280 allows up to 20 octets).
fn serial() -> Result<Asn1Integer, ErrorStack> {
    let mut n = BigNum::new()?;
    n.rand(159, MsbOption::MAYBE_ZERO, false)?;
    n.to_asn1_integer()
}

/// A v3 certificate of `key` for `subject`, issued by `issuer` and signed with `signer`.
fn certificate(
    key: &PKey<Private>,
    subject: &X509NameRef,
    issuer: &X509NameRef,
    signer: &PKey<Private>,
    validity: Validity,
    ca: bool,
) -> Result<X509, ErrorStack> {
    let mut cert = X509::builder()?;
    cert.set_version(2)?;
    let serial = serial()?;
    cert.set_serial_number(&serial)?;
    cert.set_subject_name(subject)?;
    cert.set_issuer_name(issuer)?;
    cert.set_pubkey(key)?;
    let not_before = Asn1Time::from_unix(validity.not_before)?;
    let not_after = Asn1Time::from_unix(validity.not_after)?;
    cert.set_not_before(&not_before)?;
    cert.set_not_after(&not_after)?;
    let mut constraints = BasicConstraints::new();
    constraints.critical();
    if ca {
        constraints.ca();
    }
    cert.append_extension(constraints.build()?)?;
    cert.sign(signer, MessageDigest::sha256())?;
    Ok(cert.build())
}

impl Authority {
    /// A new authority named `cn`, its certificate signed by its own key.
    pub fn new(cn: &str, validity: Validity) -> Result<Authority, ErrorStack> {
        let key = new_key()?;
        let name = common_name(cn)?;
        let cert = certificate(&key, &name, &name, &key, validity, true)?;
        Ok(Authority { key, cert })
    }

    /// The authority stored as PEM files' contents.
    pub fn from_pem(key: &[u8], cert: &[u8]) -> Result<Authority, ErrorStack> {
        Ok(Authority {
            key: PKey::private_key_from_pem(key)?,
            cert: X509::from_pem(cert)?,
        })
    }

    /// A certificate for `key`, its subject `CN=cn`, signed by this authority.
    pub fn issue(
        &self,
        key: &PKey<Private>,
        cn: &str,
        validity: Validity,
    ) -> Result<X509, ErrorStack> {
        let subject = common_name(cn)?;
        certificate(
            key,
            &subject,
            self.cert.subject_name(),
            &self.key,
            validity,
            false,
        )
    }

    /// `document` signed by this authority as S/MIME: PKCS#7, detached, text mode (the
    /// document travels in clear in the first part, the signature in the second).
    pub fn sign(&self, document: &[u8]) -> Result<Vec<u8>, ErrorStack> {
        let flags = Pkcs7Flags::TEXT | Pkcs7Flags::DETACHED;
        let no_extra_certs: Stack<X509> = Stack::new()?;
        let signed = Pkcs7::sign(&self.cert, &self.key, &no_extra_certs, document, flags)?;
        signed.to_smime(document, flags)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use openssl::x509::store::X509StoreBuilder;

    fn validity() -> Validity {
        Validity::from_day_before(1_795_000_000, 3650)
    }

    #[test]
    fn an_issued_certificate_verifies_against_its_authority_only() {
        let ca = Authority::new("composuite test CA", validity()).unwrap();
        let key = new_key().unwrap();
        let cert = ca.issue(&key, "/talker", validity()).unwrap();
        assert!(cert.verify(&ca.key).unwrap());
        let other = Authority::new("another CA", validity()).unwrap();
        assert!(!cert.verify(&other.key).unwrap());
        let cn = cert
            .subject_name()
            .entries_by_nid(Nid::COMMONNAME)
            .next()
            .unwrap();
        assert_eq!(String::from_utf8_lossy(cn.data().as_slice()), "/talker");
        assert_eq!(cert.not_after().to_string(), "Nov 14 11:06:40 2036 GMT");
    }

    #[test]
    fn a_signed_document_verifies_and_a_changed_one_does_not() {
        let ca = Authority::new("composuite test CA", validity()).unwrap();
        let document = b"<dds>governance</dds>\n";
        let smime = ca.sign(document).unwrap();
        let text = String::from_utf8(smime.clone()).unwrap();
        assert!(text.contains("multipart/signed") && text.contains("<dds>governance</dds>"));
        let mut store = X509StoreBuilder::new().unwrap();
        store.add_cert(ca.cert.clone()).unwrap();
        let store = store.build();
        let (pkcs7, content) = Pkcs7::from_smime(&smime).unwrap();
        let content = content.expect("detached content");
        let mut out = Vec::new();
        let certs = Stack::new().unwrap();
        pkcs7
            .verify(
                &certs,
                &store,
                Some(&content),
                Some(&mut out),
                Pkcs7Flags::TEXT,
            )
            .unwrap();
        // Text mode canonicalises line ends to CRLF, as S/MIME does.
        assert_eq!(
            String::from_utf8(out)
                .unwrap()
                .replace("\r\n", "\n")
                .as_bytes(),
            document
        );
        let tampered = text.replace("governance</dds>", "governancf</dds>");
        let (pkcs7, content) = Pkcs7::from_smime(tampered.as_bytes()).unwrap();
        assert!(
            pkcs7
                .verify(&certs, &store, content.as_deref(), None, Pkcs7Flags::TEXT)
                .is_err()
        );
    }
}
