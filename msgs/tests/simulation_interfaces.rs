//! The ROS 2 standard simulation interfaces (msgs/simulation_interfaces/): the files carry
//! simulation_interfaces 1.5.1 (Jazzy), so every type's RIHS01 hash must equal the one ROS 2
//! Jazzy's rosidl computes for the upstream release's own files.

use std::collections::BTreeMap;
use std::path::PathBuf;

use composuite_msgs::{MessageVisitor, RosMessage, RosService, ServiceVisitor};

const PACKAGE: &str = "simulation_interfaces";

/// The RIHS01 hashes (without the `RIHS01_` prefix) that rosidl_generator_type_description
/// writes into `share/simulation_interfaces/{msg,srv,action}/*.json` when colcon builds the
/// upstream files of release 1.5.1 (ros-simulation/simulation_interfaces, tag 1.5.1, commit
/// a3c60ff2715dbe5e9d5cddce410d9a7ffe771960) against the ros-jazzy wheels of
/// tests/py/requirements.txt. A colcon build of our files (scripts/build-msgs-colcon) writes the
/// same 116 hashes; these are the ones the Rust crate has types for: every message, each
/// service's request, response and event, and the action's goal, result and feedback.
const MESSAGE_HASHES: [(&str, &str); 84] = [
    (
        "simulation_interfaces/action/SimulateSteps_Feedback",
        "735661ca01115eb9bca068c3f2cb79bd790cd46962317ce7ee9081a5915c9a77",
    ),
    (
        "simulation_interfaces/action/SimulateSteps_Goal",
        "3f02c5df1dcdc7c08efee7f47c953c42c11686e0df8f8bbfb2d7e901f0d440d2",
    ),
    (
        "simulation_interfaces/action/SimulateSteps_Result",
        "a1384eaee4ca7ae9238e612dfe26939dd0922cae664be1b5886cf773718823dc",
    ),
    (
        "simulation_interfaces/msg/Bounds",
        "e8624fe51f0f5548197542697d924c5699ac7198f1e4c68e50c3ca2af73f5b3f",
    ),
    (
        "simulation_interfaces/msg/EntityCategory",
        "43bdf7933fddf75f6970f7a8fe7078524355d821d390b3954bb46ac36c03dfe1",
    ),
    (
        "simulation_interfaces/msg/EntityFilters",
        "8e7b12e8ea062f14c55de4877221fe1b7cd9749665a7ad8a4ab855fc4b148303",
    ),
    (
        "simulation_interfaces/msg/EntityInfo",
        "3b9a2e7fa00f9a59d325b6e47904044c421561a385682027c7fc06c359806319",
    ),
    (
        "simulation_interfaces/msg/EntityState",
        "2e0464a85eb80a939025075d6c20761eca6a4cb9d6baf2c0ba373467c8b598d0",
    ),
    (
        "simulation_interfaces/msg/NamedPose",
        "b32da2a039b1840f605ec025b7991a18efacac662fac272818d1ae6e2b12bc27",
    ),
    (
        "simulation_interfaces/msg/Resource",
        "2bb1939cf80f8d2f284afba53cbec60b5ff33759bd39b714128ea8867a34c51a",
    ),
    (
        "simulation_interfaces/msg/Result",
        "cf43a306adff3337a0a47143d8f5689933bc70a30478f13b077dc1fe3bc5ad17",
    ),
    (
        "simulation_interfaces/msg/SimulationState",
        "bb9f87ccdd98fba113052a512d9801e84ce732d0a2b3c2b0cb281828de36e415",
    ),
    (
        "simulation_interfaces/msg/SimulatorFeatures",
        "8b101c8529bc0ea3dcf056078254768f39832b9ef0adaf93bd5cea96c0de3305",
    ),
    (
        "simulation_interfaces/msg/SpawnEntity",
        "94a349a865ccf673c18c080520299c88c3d8d5f4842ecf1482d6c997ac4b69f9",
    ),
    (
        "simulation_interfaces/msg/SpawnResult",
        "dbc277304b6c24bfb2a631cea8f52e2b005d583ec0a6c86b11613f5ce6486da1",
    ),
    (
        "simulation_interfaces/msg/Spawnable",
        "8c22025d840e7a05ab31ba56f998b06458b549a9744b4695be25b778829fc176",
    ),
    (
        "simulation_interfaces/msg/TagsFilter",
        "5c3efc51e8ed04c266c09cb4691ec95b964cd410558e01d8c83646b038826b45",
    ),
    (
        "simulation_interfaces/msg/WorldResource",
        "e3b65ecf904b9b115673e4a343c6aa3d28c19e185a71228faa64b783afcf2403",
    ),
    (
        "simulation_interfaces/srv/DeleteEntity_Event",
        "6850423be1d45755566343794fb56be8ff3c90fc87706b7ea939764499a9d773",
    ),
    (
        "simulation_interfaces/srv/DeleteEntity_Request",
        "4b41b2ebdc313a0c98c7c2218849edc8b7b905fd759a23b68c576496a47dc792",
    ),
    (
        "simulation_interfaces/srv/DeleteEntity_Response",
        "2f68929b527a3bbee03637a1c8192f2aa2982807738389aa0781f8e785673ca7",
    ),
    (
        "simulation_interfaces/srv/GetAvailableWorlds_Event",
        "d3ddd4cef845a1d6fbe402a376963b1fbcedd066fdd9b7afccd32fac73ec9135",
    ),
    (
        "simulation_interfaces/srv/GetAvailableWorlds_Request",
        "6335180e35038ba62eb2bae3d1c1bacd4b7791209137eacbddfee12629bf6c3a",
    ),
    (
        "simulation_interfaces/srv/GetAvailableWorlds_Response",
        "0ce98a1547f1852fd6d95f794ae4bae8b1d97b9cfa83ea22b80f634999234a18",
    ),
    (
        "simulation_interfaces/srv/GetCurrentWorld_Event",
        "902c9e9dbb35203e71f734410d7b8c0ec94fa8191fb04287a936a72dd713d5c0",
    ),
    (
        "simulation_interfaces/srv/GetCurrentWorld_Request",
        "414ac6e1c5fd5f8be0b828ca7ff8cbee7166297809de31a36129f1d0913cd877",
    ),
    (
        "simulation_interfaces/srv/GetCurrentWorld_Response",
        "039f99eb4e156ac597efed7598249921f8e47e5bff8c299d86ab081983a3a52a",
    ),
    (
        "simulation_interfaces/srv/GetEntitiesStates_Event",
        "3bfcf28a7087002f7f5be3539f5d069b660227c3f81e0e3195981e13a56d8b3d",
    ),
    (
        "simulation_interfaces/srv/GetEntitiesStates_Request",
        "0af5302d3526834e83bd9861fbcc5214af2b9a4b0c93a965840fb1a6c2891724",
    ),
    (
        "simulation_interfaces/srv/GetEntitiesStates_Response",
        "b651848f4d93a2b0ec5ec3f36659297ca30547c499f933eb279b60f8be434315",
    ),
    (
        "simulation_interfaces/srv/GetEntities_Event",
        "c26cff3c94ca0df967f9f223af89340dcb6becb05b9d32544eb84cac0e85ca8d",
    ),
    (
        "simulation_interfaces/srv/GetEntities_Request",
        "f0a4c6c0c39c87f84cbd1ea31956b9f39b3fa538ae9c4aa7fc243a32360e8c70",
    ),
    (
        "simulation_interfaces/srv/GetEntities_Response",
        "dd1916edbdc659d355e77980b16ed6eb4d41d5ff445557931ed65c58b00f7b2c",
    ),
    (
        "simulation_interfaces/srv/GetEntityBounds_Event",
        "12525654c3c1271da06ce976dd1ab72920fbe3879768c4b53f1074b9b98f05bb",
    ),
    (
        "simulation_interfaces/srv/GetEntityBounds_Request",
        "41766afd481abfa03a9dface86a487e317da516333af3f5b017df248dd5d7fee",
    ),
    (
        "simulation_interfaces/srv/GetEntityBounds_Response",
        "728d414a3be6d7689fad9d3218c8378c68fbe08c2cfbf9878ac14de713fcf4c1",
    ),
    (
        "simulation_interfaces/srv/GetEntityInfo_Event",
        "925bdd1efc19b29c5548add7ffa4a7821b5533d90f25d73673d8978f9f0ad206",
    ),
    (
        "simulation_interfaces/srv/GetEntityInfo_Request",
        "9bdd2628d931108734e304ae1fac80d268a46783fa0060d4a43831c54c30f3b3",
    ),
    (
        "simulation_interfaces/srv/GetEntityInfo_Response",
        "eaa358f007b09b06645f93b5a1c6ae0389f27bee7747e760122994ab1308e1c8",
    ),
    (
        "simulation_interfaces/srv/GetEntityState_Event",
        "5c4a353980893294fce5fca5a1359ec0c821578acc263f56db8042b35ced68e6",
    ),
    (
        "simulation_interfaces/srv/GetEntityState_Request",
        "580141cc957c4ee99a7e46bc545db351ab9ce6c3099d4092b1186ddc6a38bd5a",
    ),
    (
        "simulation_interfaces/srv/GetEntityState_Response",
        "125f1ca9dc2fc072443deb28587bbb1026fa34db4dfaf59e9a6b7128e0c81331",
    ),
    (
        "simulation_interfaces/srv/GetNamedPoseBounds_Event",
        "b3e0f071e2350276bc9f5ac23a19b0a7dcaea7add138439ccd986b22db4aad0a",
    ),
    (
        "simulation_interfaces/srv/GetNamedPoseBounds_Request",
        "4a62596dff6478d6424267da8933b1446992f61c70c2c196aa36258a1f1d133f",
    ),
    (
        "simulation_interfaces/srv/GetNamedPoseBounds_Response",
        "db03610df68de520b420ccc9dc8826a92547ab9e791ac2a36a7dc86e8f2aa180",
    ),
    (
        "simulation_interfaces/srv/GetNamedPoses_Event",
        "721dfb79239fd5585b94ec7f18046c7d08f8aa97d0755bbad3b27ac32a165393",
    ),
    (
        "simulation_interfaces/srv/GetNamedPoses_Request",
        "3d85f7553c5fcb491256b6eab66204ee590edbd0ad2dd53bb4ddf8a95f16af6e",
    ),
    (
        "simulation_interfaces/srv/GetNamedPoses_Response",
        "d0459c9da6adb831b3755778bc348cc88ad2b22fe864a11062df20610a12c320",
    ),
    (
        "simulation_interfaces/srv/GetSimulationState_Event",
        "34cdb4f06989af235d3403650bae196550a928870b69740899fadc922899748f",
    ),
    (
        "simulation_interfaces/srv/GetSimulationState_Request",
        "c6d65bc5c0a95ca2886bc57f146f803e01722c84ddb5acd5f32a4417f55eecfb",
    ),
    (
        "simulation_interfaces/srv/GetSimulationState_Response",
        "dc80ce852a5ab04c2b23cdd47910cee1bcc46e0f1931cac85825e6916b15517f",
    ),
    (
        "simulation_interfaces/srv/GetSimulatorFeatures_Event",
        "2716384dc5445ebe9e7eda1021e5739b8c62ab985dccc3c506ba840c67e810b8",
    ),
    (
        "simulation_interfaces/srv/GetSimulatorFeatures_Request",
        "982b8c1adef1d556f6ecdc019d1269fc39413626a9222d73b4fc874bd798b7db",
    ),
    (
        "simulation_interfaces/srv/GetSimulatorFeatures_Response",
        "ede4dc8227cbb2f86a24612c999dcaa67d17dab21dab566cefdc233e7a2a65d1",
    ),
    (
        "simulation_interfaces/srv/GetSpawnables_Event",
        "e80a5cad9a3792e0a068c0d9782647cc26d3701e77af0743a757e1c264b0f58b",
    ),
    (
        "simulation_interfaces/srv/GetSpawnables_Request",
        "3e1d1577446a80da956db3e82363c2d66364f9802f6e9572d89497933207d921",
    ),
    (
        "simulation_interfaces/srv/GetSpawnables_Response",
        "4e532ac531e2d0bb495a8b53409a8025551f55329250537a3d5a28c5d7ce36af",
    ),
    (
        "simulation_interfaces/srv/LoadWorld_Event",
        "1b36da46dafd603502b9945ff4f01b1154d639d8d475da00e3b4227233b2b172",
    ),
    (
        "simulation_interfaces/srv/LoadWorld_Request",
        "f683da497d911d5b8d8191c457d4dd90b39ceb1a7c3ec8e2f2adf89ee6721851",
    ),
    (
        "simulation_interfaces/srv/LoadWorld_Response",
        "7bab3265c2461d98a44dd04830c5dc997b3d8605c50861824066246c96a7716e",
    ),
    (
        "simulation_interfaces/srv/ResetSimulation_Event",
        "dd7cbcb886e466ab23216c7033f25e8534e5255a73877944338bb301e7b29626",
    ),
    (
        "simulation_interfaces/srv/ResetSimulation_Request",
        "2c766d09c3aa30f01fadc55a42fd760b63db358c7d1d3b6a64ea9978225ffbc7",
    ),
    (
        "simulation_interfaces/srv/ResetSimulation_Response",
        "718428121e0f1755720878d3c28f1688da7581ee5a5d56d26d10d941a28a50a0",
    ),
    (
        "simulation_interfaces/srv/SetEntityInfo_Event",
        "02fa040f4ae8a026ed9f8b9dbd09c589fbce019f9e3623b3c90e076e8ee9fe75",
    ),
    (
        "simulation_interfaces/srv/SetEntityInfo_Request",
        "d80ba71f092c702485bdffcd35713793866df4e1a16ace6632c6d4a15bb1eb55",
    ),
    (
        "simulation_interfaces/srv/SetEntityInfo_Response",
        "d17b31f0f6db0146ceb0b711d47dbf81c9c11c87ca4f64cfa671a95d9723c3d6",
    ),
    (
        "simulation_interfaces/srv/SetEntityState_Event",
        "4dbb2f7b3b12af1b7b3cf68402e09994422fe76008b1efa7580a3a9386fa40d0",
    ),
    (
        "simulation_interfaces/srv/SetEntityState_Request",
        "95cdfbffcd9c4d0133b2079bdcadd4420ce86dd255c11a3dfed7f9f907fd304d",
    ),
    (
        "simulation_interfaces/srv/SetEntityState_Response",
        "bbd9bcb2def000f1ed8cb9482abff46c5a11cfe4184203f336b920f249d757f4",
    ),
    (
        "simulation_interfaces/srv/SetSimulationState_Event",
        "aea08cbc96bd8c6c88ba9ab79f98a73bf3028c35ea8e1f47bf5fc9d82cbc6b9a",
    ),
    (
        "simulation_interfaces/srv/SetSimulationState_Request",
        "73283477d36ba619db2ac37a3e599077ca244502c9d8ca2a7183afcb2224f476",
    ),
    (
        "simulation_interfaces/srv/SetSimulationState_Response",
        "6351aebf2bbf06e2993977918b944240f7403b532a9e4a344c53e71a56afd174",
    ),
    (
        "simulation_interfaces/srv/SpawnEntities_Event",
        "2ad607727595abd8bd06e3eab4a425615c44b370837a266b3d654994dfa87ee0",
    ),
    (
        "simulation_interfaces/srv/SpawnEntities_Request",
        "03f070057ac2ab26d723fe9f07c7d57bd39ace34ad34bb043cdbca36825c98d9",
    ),
    (
        "simulation_interfaces/srv/SpawnEntities_Response",
        "85df56d44250220df64762bf3e769cce45f84730eff8b9823093ca3041ecbbf5",
    ),
    (
        "simulation_interfaces/srv/SpawnEntity_Event",
        "05e6108bc39b5953a6163952541a1cec1991a74558a128c65b03b27b3ec34c61",
    ),
    (
        "simulation_interfaces/srv/SpawnEntity_Request",
        "fdcf97087f59eed1ad0b75696ea97ffbb44d104f62f177fcd5a31ab67c6fc923",
    ),
    (
        "simulation_interfaces/srv/SpawnEntity_Response",
        "be8c9fc03b6faaf95570949c80195c8ca75dd99f7efc23262309d497b2923982",
    ),
    (
        "simulation_interfaces/srv/StepSimulation_Event",
        "1796fda54ba381a56d32c10784cabf78e14d6c8a1912a515a47d6597ad431d90",
    ),
    (
        "simulation_interfaces/srv/StepSimulation_Request",
        "cda33f6887815f3dce0f90e61fd8efd39bda13ae264ddede15c33fbad890630e",
    ),
    (
        "simulation_interfaces/srv/StepSimulation_Response",
        "5b4acf2d0ce7c3fc125d0bef2acb9b5a81377e80db6b696b81beeffb9824fb5c",
    ),
    (
        "simulation_interfaces/srv/UnloadWorld_Event",
        "3162d5a68097988260c3a9a65cfd99f788a4a0b00d164bff67a5e7230cbff829",
    ),
    (
        "simulation_interfaces/srv/UnloadWorld_Request",
        "22b41a53aecd3cd180a218b16d9428cddc10b9e592ae16eaa434be873387e972",
    ),
    (
        "simulation_interfaces/srv/UnloadWorld_Response",
        "68d4ea5721903837edd7c7e90d86e62aafb861c1ace33b7c805931974a652d9e",
    ),
];

/// The services' own hashes, from the same files.
const SERVICE_HASHES: [(&str, &str); 22] = [
    (
        "simulation_interfaces/srv/DeleteEntity",
        "ff7e96a5b83dc8e2bb34b8b034480028b3a24d9f8376b2c0590bac3704be3e28",
    ),
    (
        "simulation_interfaces/srv/GetAvailableWorlds",
        "ce5589b5523f2732d1969a3c5a7e6b17a387091df8190c62f78d7fdd1109e3e3",
    ),
    (
        "simulation_interfaces/srv/GetCurrentWorld",
        "79ed4e910e1b7a1c9f7950ff758bfba3535bf0dec669054e8af115a099724ddd",
    ),
    (
        "simulation_interfaces/srv/GetEntities",
        "cb90004c48cd50f37732fb008e22c34c261dd680a723bf0f85d8437ea4498bf7",
    ),
    (
        "simulation_interfaces/srv/GetEntitiesStates",
        "0a76170d0c1c90e1eaf805cfab78ea801d1f82df309a28c1f0fae4b570f19754",
    ),
    (
        "simulation_interfaces/srv/GetEntityBounds",
        "17be8d36231178a5eed0de0344b55c19975581627a9aec30a4fee9926a35deed",
    ),
    (
        "simulation_interfaces/srv/GetEntityInfo",
        "953b7ab6bfc35063f5c9a72463c6ce489baa10249a7fa510926d342a34b0d29e",
    ),
    (
        "simulation_interfaces/srv/GetEntityState",
        "749c91f2a2353d98367b64f2995a0f5842ce92a08ec1ffb3e185540a91557fb5",
    ),
    (
        "simulation_interfaces/srv/GetNamedPoseBounds",
        "59fa8dd2c68ba6771160cc66a628ac99fa95e2748fa0a43c2cc62a2e5f3f6fdc",
    ),
    (
        "simulation_interfaces/srv/GetNamedPoses",
        "c3d12ab920115bfd4733f6d20516adc3968fb438538540997c37e200e02b04e3",
    ),
    (
        "simulation_interfaces/srv/GetSimulationState",
        "3362dcebee4b1afebbf9c4beee5c79c1455385aded62092a892d61fde8644f30",
    ),
    (
        "simulation_interfaces/srv/GetSimulatorFeatures",
        "abb9439c8cf196722a469fb6c68b44b484f198c2a1356ac38849a29c2a20a794",
    ),
    (
        "simulation_interfaces/srv/GetSpawnables",
        "3bc0266bf8236058ff589c44512e013afe4f295427c39d44cff363d1c956bf36",
    ),
    (
        "simulation_interfaces/srv/LoadWorld",
        "f210682338f195f6f06191b46b20ec4992bddf485d33e2cffab2dd15341b4e3e",
    ),
    (
        "simulation_interfaces/srv/ResetSimulation",
        "4ce285d7ff9b8ac70dcc95161f32bf54c05a6f4b13427990e41ab40c36c39646",
    ),
    (
        "simulation_interfaces/srv/SetEntityInfo",
        "867fe2b6812f3e021859171f9b788560d66bb7079d640030baf6c0bb2dd2631e",
    ),
    (
        "simulation_interfaces/srv/SetEntityState",
        "ca210e7d2b66629ae133c8e1edf5246e618106d75c78ed0556c0e7a33c59ee5e",
    ),
    (
        "simulation_interfaces/srv/SetSimulationState",
        "a868b916dce49974f637ba252141258c4b07b0c06858b88af560e3eb6bfbcb30",
    ),
    (
        "simulation_interfaces/srv/SpawnEntities",
        "41703a359ee032bf4fc230f144f531705ba039a2e97edeae1f7997dd83b04857",
    ),
    (
        "simulation_interfaces/srv/SpawnEntity",
        "d4c086345d4194a5fc4c9ae45095736ca4062b5cdac4d06a42dec93d683e03cf",
    ),
    (
        "simulation_interfaces/srv/StepSimulation",
        "913fe0653690ce6bf8f09f316e6a626747012e9fca31e26719910d417aa8565c",
    ),
    (
        "simulation_interfaces/srv/UnloadWorld",
        "ac7f9a73df1b5b15015d854c5ac552b7726506e22f886c6792804f0b7f88b30b",
    ),
];

fn package_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("simulation_interfaces")
        .join(PACKAGE)
}

struct Messages(BTreeMap<&'static str, &'static str>);
impl MessageVisitor for Messages {
    fn visit<T: RosMessage>(&mut self) {
        if T::ROS_NAME.starts_with("simulation_interfaces/") {
            self.0.insert(T::ROS_NAME, T::TYPE_HASH);
        }
    }
}

struct Services(BTreeMap<&'static str, &'static str>);
impl ServiceVisitor for Services {
    fn visit<S: RosService>(&mut self) {
        if S::ROS_NAME.starts_with("simulation_interfaces/") {
            self.0.insert(S::ROS_NAME, S::TYPE_HASH);
        }
    }
}

fn pinned(pins: &[(&'static str, &'static str)]) -> BTreeMap<&'static str, String> {
    pins.iter()
        .map(|(name, hash)| (*name, format!("RIHS01_{hash}")))
        .collect()
}

#[test]
fn simulation_interfaces_type_hashes_equal_upstream_1_5_1() {
    let mut messages = Messages(BTreeMap::new());
    composuite_msgs::visit_messages(&mut messages);
    let ours: BTreeMap<_, _> = messages
        .0
        .into_iter()
        .map(|(n, h)| (n, h.to_string()))
        .collect();
    // Equal maps: the same set of types (none missing, none extra) and the same hashes.
    assert_eq!(ours, pinned(&MESSAGE_HASHES));

    let mut services = Services(BTreeMap::new());
    composuite_msgs::visit_services(&mut services);
    let ours: BTreeMap<_, _> = services
        .0
        .into_iter()
        .map(|(n, h)| (n, h.to_string()))
        .collect();
    assert_eq!(ours, pinned(&SERVICE_HASHES));
}

#[test]
fn every_interface_file_is_pinned_and_listed_in_cmake() {
    let mut on_disk = Vec::new();
    for kind in ["msg", "srv", "action"] {
        for entry in std::fs::read_dir(package_dir().join(kind)).unwrap() {
            let path = entry.unwrap().path();
            if path.extension().is_some_and(|e| e == kind) {
                let stem = path.file_stem().unwrap().to_str().unwrap().to_string();
                on_disk.push(format!("{kind}/{stem}.{kind}"));
            }
        }
    }
    on_disk.sort();
    assert_eq!(on_disk.len(), 15 + 22 + 1);

    // CMakeLists.txt lists exactly these files, each once.
    let cmake = std::fs::read_to_string(package_dir().join("CMakeLists.txt")).unwrap();
    let mut listed: Vec<String> = cmake
        .split('"')
        .skip(1)
        .step_by(2)
        .filter(|s| s.starts_with("msg/") || s.starts_with("srv/") || s.starts_with("action/"))
        .map(str::to_string)
        .collect();
    listed.sort();
    assert_eq!(listed, on_disk);

    // Each file has its pins: a message; a service's request, response and event; the action's
    // goal, result and feedback.
    let names: Vec<&str> = MESSAGE_HASHES.iter().map(|(n, _)| *n).collect();
    for file in &on_disk {
        let (kind, rest) = file.split_once('/').unwrap();
        let stem = rest.split_once('.').unwrap().0;
        let parts: &[&str] = match kind {
            "msg" => &[""],
            "srv" => &["_Request", "_Response", "_Event"],
            _ => &["_Goal", "_Result", "_Feedback"],
        };
        for part in parts {
            let name = format!("{PACKAGE}/{kind}/{stem}{part}");
            assert!(names.contains(&name.as_str()), "{name} is not pinned");
        }
    }
}

#[test]
fn defaults_and_constants_come_from_the_files() {
    use composuite_msgs::simulation_interfaces::{action, msg, srv};
    assert_eq!(srv::StepSimulationRequest::default().steps, 1);
    assert_eq!(action::SimulateStepsGoal::default().steps, 0);
    assert_eq!(msg::Result::RESULT_OK, 1);
    assert_eq!(msg::SimulationState::STATE_LOADING_WORLD, 5);
    assert_eq!(msg::SimulatorFeatures::SPAWNING_ENTITIES, 50);
    assert_eq!(msg::EntityCategory::CATEGORY_STATIC_OBJECT, 5);
    assert_eq!(srv::ResetSimulationRequest::SCOPE_ALL, 255);
    assert_eq!(srv::SetEntityStateResponse::INVALID_POSE, 101);
    assert_eq!(srv::SpawnEntitiesResponse::ENTITIES_SPAWN_FAILED, 150);
    // Jazzy's SetEntityState request is just the entity and its state (no `set_*` flags), and its
    // SpawnEntity request has flat `uri`/`resource_string` fields.
    let fields = |d: &composuite_msgs::TypeDescription| -> Vec<&str> {
        d.fields.iter().map(|f| f.name).collect()
    };
    assert_eq!(
        fields(<srv::SetEntityStateRequest as RosMessage>::DESCRIPTION),
        ["entity", "state"]
    );
    assert_eq!(
        fields(<srv::SpawnEntityRequest as RosMessage>::DESCRIPTION),
        [
            "name",
            "allow_renaming",
            "uri",
            "resource_string",
            "entity_namespace",
            "initial_pose"
        ]
    );
}
