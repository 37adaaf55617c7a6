//! The two XML documents of DDS-Security's builtin access control (OMG DDS-Security 1.1, the
//! 2017-09-01 schemas), as `ros2 security` writes them by default: the domain's governance
//! (what is protected, and how) and an enclave's permissions (what it may publish and
//! subscribe to).

/// The governance of `domain`: no unauthenticated participants, joining checked against the
/// permissions, discovery and liveliness encrypted, every RTPS message signed, and on every
/// topic read and write access checked with metadata and data encrypted.
pub fn governance(domain: u32) -> String {
    format!(
        r#"<?xml version="1.0" encoding="UTF-8"?>
<dds xmlns:xsi="http://www.w3.org/2001/XMLSchema-instance" xsi:noNamespaceSchemaLocation="http://www.omg.org/spec/DDS-SECURITY/20170901/omg_shared_ca_governance.xsd">
  <domain_access_rules>
    <domain_rule>
      <domains>
        <id>{domain}</id>
      </domains>
      <allow_unauthenticated_participants>false</allow_unauthenticated_participants>
      <enable_join_access_control>true</enable_join_access_control>
      <discovery_protection_kind>ENCRYPT</discovery_protection_kind>
      <liveliness_protection_kind>ENCRYPT</liveliness_protection_kind>
      <rtps_protection_kind>SIGN</rtps_protection_kind>
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

/// What an enclave may do on the wire: DDS topic names (with `*` and `?` wildcards) it may
/// publish and subscribe to.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Grant {
    /// Topics it may write.
    pub publish: Vec<String>,
    /// Topics it may read.
    pub subscribe: Vec<String>,
}

impl Grant {
    /// What `ros2 security create_enclave` grants without a policy: every ROS topic (`rt/`),
    /// service request (`rq/`) and reply (`rr/`) both ways, and the graph's
    /// `ros_discovery_info`.
    pub fn ros_default() -> Grant {
        let all: Vec<String> = ["rq/*", "rr/*", "rt/*", "ros_discovery_info"]
            .map(String::from)
            .into();
        Grant {
            publish: all.clone(),
            subscribe: all,
        }
    }
}

impl Grant {
    /// Exactly these topics, and the graph's `ros_discovery_info` both ways (every ROS 2
    /// participant publishes and reads it).
    pub fn of(publish: &[String], subscribe: &[String]) -> Grant {
        let with_discovery = |topics: &[String]| {
            let mut all = topics.to_vec();
            if !all.iter().any(|t| t == "ros_discovery_info") {
                all.push("ros_discovery_info".into());
            }
            all
        };
        Grant {
            publish: with_discovery(publish),
            subscribe: with_discovery(subscribe),
        }
    }
}

/// The XML-escaped form of `text` (enclave names and topics are plain ROS names; this keeps a
/// stray `&` or `<` from breaking the document).
fn escape(text: &str) -> String {
    text.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

fn topics(indent: &str, names: &[String]) -> String {
    names
        .iter()
        .map(|t| format!("{indent}<topic>{}</topic>\n", escape(t)))
        .collect()
}

/// The permissions of `enclave` (its certificate's subject is `CN=<enclave>`) on `domain`,
/// valid between two UTC times written `YYYY-MM-DDTHH:MM:SS`; anything `grant` does not allow
/// is denied.
pub fn permissions(
    enclave: &str,
    domain: u32,
    not_before: &str,
    not_after: &str,
    grant: &Grant,
) -> String {
    let enclave = escape(enclave);
    let inner = "              ";
    format!(
        r#"<?xml version="1.0" encoding="UTF-8"?>
<dds xmlns:xsi="http://www.w3.org/2001/XMLSchema-instance" xsi:noNamespaceSchemaLocation="http://www.omg.org/spec/DDS-SECURITY/20170901/omg_shared_ca_permissions.xsd">
  <permissions>
    <grant name="{enclave}">
      <subject_name>CN={enclave}</subject_name>
      <validity>
        <not_before>{not_before}</not_before>
        <not_after>{not_after}</not_after>
      </validity>
      <allow_rule>
        <domains>
          <id>{domain}</id>
        </domains>
        <publish>
          <topics>
{publish}          </topics>
        </publish>
        <subscribe>
          <topics>
{subscribe}          </topics>
        </subscribe>
      </allow_rule>
      <default>DENY</default>
    </grant>
  </permissions>
</dds>
"#,
        publish = topics(inner, &grant.publish),
        subscribe = topics(inner, &grant.subscribe),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_governance_names_its_domain_and_protects_everything() {
        let xml = governance(7);
        assert!(xml.contains("<id>7</id>"));
        assert!(xml.contains("<allow_unauthenticated_participants>false<"));
        assert!(xml.contains("<data_protection_kind>ENCRYPT<"));
        assert!(xml.contains("<topic_expression>*</topic_expression>"));
    }

    #[test]
    fn permissions_grant_the_enclave_what_it_is_given_and_deny_the_rest() {
        let grant = Grant {
            publish: vec!["rt/joint_command".into()],
            subscribe: vec!["rt/observation".into(), "a<b".into()],
        };
        let xml = permissions(
            "/agent",
            0,
            "2026-11-28T00:00:00",
            "2036-11-26T00:00:00",
            &grant,
        );
        assert!(xml.contains(r#"<grant name="/agent">"#));
        assert!(xml.contains("<subject_name>CN=/agent</subject_name>"));
        assert!(xml.contains("<not_after>2036-11-26T00:00:00</not_after>"));
        let publish = &xml[xml.find("<publish>").unwrap()..xml.find("</publish>").unwrap()];
        assert!(publish.contains("<topic>rt/joint_command</topic>"));
        assert!(!publish.contains("rt/observation"));
        assert!(xml.contains("<topic>a&lt;b</topic>"));
        assert!(xml.trim_end().ends_with("</dds>") && xml.contains("<default>DENY</default>"));
        let default = Grant::ros_default();
        assert_eq!(
            default.publish,
            ["rq/*", "rr/*", "rt/*", "ros_discovery_info"]
        );
        assert_eq!(default.publish, default.subscribe);
    }
}
