//! sros2's policy files (format 0.2.0, what `ros2 security create_permission` and
//! `create_enclave --policy` read): per enclave, profiles of nodes (`ns`, `node`) with the
//! topics they publish and subscribe to, the services they serve (`reply`) and call
//! (`request`), and the actions they serve (`execute`) and call (`call`). Turned into the DDS
//! topics of a [`Grant`] as sros2 turns them into permissions: a name is absolute (`/x`),
//! relative to the profile's namespace (`x`) or private to its node (`~x`).
//!
//! Every profile also gets what each ROS node has — the log, parameter events and its parameter
//! services — which sros2's policies pull in from its own `common/node.xml` with an XInclude;
//! those includes are not read (`common/` ones are what this adds; another is refused).

use composuite_ros::grants::Topics;
use roxmltree::{Document, Node};

use super::documents::Grant;

/// The grant of `enclave` in the policy document `xml` (named `file` in errors).
pub fn grant_from_policy(xml: &str, file: &str, enclave: &str) -> Result<Grant, String> {
    let doc = Document::parse(xml).map_err(|e| format!("{file}: not XML: {e}"))?;
    let root = doc.root_element();
    if root.tag_name().name() != "policy" {
        return Err(format!(
            "{file}: not an sros2 policy (its root is <{}>, not <policy>)",
            root.tag_name().name()
        ));
    }
    let enclaves: Vec<Node> = root
        .descendants()
        .filter(|n| n.has_tag_name("enclave"))
        .collect();
    let Some(chosen) = enclaves
        .iter()
        .find(|e| e.attribute("path") == Some(enclave))
    else {
        let paths: Vec<&str> = enclaves
            .iter()
            .filter_map(|e| e.attribute("path"))
            .collect();
        return Err(format!(
            "{file} has no enclave {enclave}; it has: {}",
            if paths.is_empty() {
                "none".to_string()
            } else {
                paths.join(", ")
            }
        ));
    };
    let mut topics = Topics::default();
    for profile in chosen.descendants().filter(|n| n.has_tag_name("profile")) {
        let ns = profile.attribute("ns").unwrap_or("/");
        let node = profile
            .attribute("node")
            .ok_or_else(|| format!("{file}: a <profile> of {enclave} has no node=\"…\""))?;
        let names = Names { ns, node };
        // What sros2's `common/node.xml` gives every node.
        topics.subscribe_topic("/", "parameter_events");
        topics.ros_node(&format!("/{}", ns.trim_matches('/')), node);
        for element in profile.children().filter(Node::is_element) {
            grant_element(&mut topics, &element, &names, file)?;
        }
    }
    Ok(Grant::of(&topics.publish, &topics.subscribe))
}

/// A profile's node and namespace, to resolve names with.
struct Names<'a> {
    ns: &'a str,
    node: &'a str,
}

impl Names<'_> {
    /// `name` made absolute, without its leading `/`.
    fn resolve(&self, name: &str) -> String {
        let ns = self.ns.trim_matches('/');
        let joined = if let Some(absolute) = name.strip_prefix('/') {
            absolute.to_string()
        } else if let Some(private) = name.strip_prefix('~') {
            format!("{ns}/{}/{}", self.node, private.trim_start_matches('/'))
        } else {
            format!("{ns}/{name}")
        };
        joined.trim_start_matches('/').to_string()
    }
}

/// One element of a profile: `<topics>`, `<services>` or `<actions>` with its permissions as
/// attributes and the names as children.
fn grant_element(
    topics: &mut Topics,
    element: &Node,
    names: &Names,
    file: &str,
) -> Result<(), String> {
    let tag = element.tag_name().name();
    if tag == "include" {
        let href = element.attribute("href").unwrap_or("");
        if href.contains("common/") {
            return Ok(()); // What every profile gets anyway.
        }
        return Err(format!(
            "{file}: <xi:include href=\"{href}\">: only sros2's common/ includes are \
             understood (their content is added to every profile); inline the others"
        ));
    }
    let (child, modes): (&str, &[&str]) = match tag {
        "topics" => ("topic", &["publish", "subscribe"]),
        "services" => ("service", &["reply", "request"]),
        "actions" => ("action", &["execute", "call"]),
        other => {
            return Err(format!(
                "{file}: <{other}> in a profile: valid are <topics>, <services>, <actions>"
            ));
        }
    };
    let items: Vec<String> = element
        .children()
        .filter(|n| n.has_tag_name(child))
        .map(|n| names.resolve(n.text().unwrap_or("").trim()))
        .collect();
    for attribute in element.attributes() {
        let mode = attribute.name();
        if !modes.contains(&mode) {
            return Err(format!(
                "{file}: <{tag} {mode}=…>: valid are {}",
                modes.join(" and ")
            ));
        }
        match attribute.value() {
            "ALLOW" => {}
            "DENY" => {
                return Err(format!(
                    "{file}: <{tag} {mode}=\"DENY\">: deny rules are not supported here; the \
                     permissions deny whatever is not allowed, so leave them out"
                ));
            }
            other => {
                return Err(format!(
                    "{file}: <{tag} {mode}=\"{other}\">: valid are ALLOW and DENY"
                ));
            }
        }
        for name in &items {
            grant(topics, mode, name);
        }
    }
    Ok(())
}

/// What `mode` on the resolved `name` (absolute, without its `/`) allows.
fn grant(topics: &mut Topics, mode: &str, name: &str) {
    match mode {
        "publish" => topics.publish_topic("/", name),
        "subscribe" => topics.subscribe_topic("/", name),
        "reply" => topics.serve("/", name),
        "request" => topics.call("/", name),
        "execute" => topics.serve_action("/", name),
        "call" => topics.call_action("/", name),
        _ => unreachable!("modes are checked by the caller"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const POLICY: &str = r#"<?xml version="1.0" encoding="UTF-8"?>
<policy version="0.2.0" xmlns:xi="http://www.w3.org/2001/XInclude">
  <enclaves>
    <enclave path="/agents/one">
      <profiles>
        <profile ns="/env_00" node="agent">
          <xi:include href="common/node.xml" xpointer="xpointer(/profile/*)"/>
          <topics publish="ALLOW">
            <topic>joint_command</topic>
            <topic>/diagnostics</topic>
          </topics>
          <topics subscribe="ALLOW">
            <topic>observation</topic>
            <topic>~debug</topic>
          </topics>
          <services request="ALLOW"><service>reset</service></services>
          <actions call="ALLOW"><action>simulate_steps</action></actions>
        </profile>
      </profiles>
    </enclave>
    <enclave path="/other"><profiles/></enclave>
  </enclaves>
</policy>
"#;

    /// Names resolve as sros2 resolves them (relative to the profile's namespace, absolute,
    /// private), each kind of permission becomes its DDS topics, and every profile gets what
    /// sros2's common node profile gives.
    #[test]
    fn a_policy_becomes_the_dds_topics_of_its_enclave() {
        let g = grant_from_policy(POLICY, "p.xml", "/agents/one").unwrap();
        for p in [
            "rt/env_00/joint_command",
            "rt/diagnostics",
            "rq/env_00/resetRequest",
            "rq/env_00/simulate_steps/_action/send_goalRequest",
            "rt/rosout",
            "rr/env_00/agent/get_parametersReply",
            "ros_discovery_info",
        ] {
            assert!(
                g.publish.iter().any(|x| x == p),
                "publish {p}: {:?}",
                g.publish
            );
        }
        for s in [
            "rt/env_00/observation",
            "rt/env_00/agent/debug",
            "rr/env_00/resetReply",
            "rt/env_00/simulate_steps/_action/status",
            "rq/env_00/agent/get_parametersRequest",
        ] {
            assert!(g.subscribe.iter().any(|x| x == s), "subscribe {s}");
        }
        assert!(!g.publish.iter().any(|x| x == "rt/env_00/observation"));
    }

    #[test]
    fn what_the_policy_does_not_say_or_this_tool_does_not_do_is_refused_saying_why() {
        let err = grant_from_policy(POLICY, "p.xml", "/agents/two").unwrap_err();
        assert_eq!(
            err,
            "p.xml has no enclave /agents/two; it has: /agents/one, /other"
        );
        let err = grant_from_policy("<dds/>", "p.xml", "/x").unwrap_err();
        assert!(err.contains("not an sros2 policy"), "{err}");
        let err = grant_from_policy("<policy", "p.xml", "/x").unwrap_err();
        assert!(err.starts_with("p.xml: not XML"), "{err}");
        let deny = POLICY.replace(r#"publish="ALLOW""#, r#"publish="DENY""#);
        let err = grant_from_policy(&deny, "p.xml", "/agents/one").unwrap_err();
        assert!(err.contains("deny rules are not supported"), "{err}");
        let typo = POLICY.replace(r#"request="ALLOW""#, r#"requests="ALLOW""#);
        let err = grant_from_policy(&typo, "p.xml", "/agents/one").unwrap_err();
        assert!(err.contains("valid are reply and request"), "{err}");
        let include = POLICY.replace("common/node.xml", "mine/extra.xml");
        let err = grant_from_policy(&include, "p.xml", "/agents/one").unwrap_err();
        assert!(err.contains("inline the others"), "{err}");
    }
}
