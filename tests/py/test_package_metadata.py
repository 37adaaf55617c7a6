"""composuite_msgs is a well-formed ROS 2 interface package: package.xml validates as format 3
(with catkin_pkg, the parser colcon and rosdep use) and declares what an interface package must,
and CMakeLists.txt lists exactly the .msg/.srv files that exist."""

from __future__ import annotations

import re

import msgcheck


def test_package_xml_is_a_format_3_interface_package():
    from catkin_pkg.package import parse_package

    package = parse_package(str(msgcheck.MSGS / "package.xml"))  # validates, raises if invalid
    assert package.package_format == 3
    assert package.name == "composuite_msgs"
    assert {d.name for d in package.buildtool_depends} >= {"ament_cmake", "rosidl_default_generators"}
    assert "rosidl_default_runtime" in {d.name for d in package.exec_depends}
    assert "rosidl_interface_packages" in {g.name for g in package.member_of_groups}
    assert package.get_build_type() == "ament_cmake"
    assert package.licenses and package.maintainers and package.description


def referenced_packages() -> set[str]:
    """Packages our .msg/.srv files refer to by `pkg/Type`."""
    refs = set()
    for path in [*(msgcheck.MSGS / "msg").glob("*.msg"), *(msgcheck.MSGS / "srv").glob("*.srv")]:
        for line in path.read_text().splitlines():
            line = line.split("#", 1)[0].strip()
            match = re.match(r"([a-z][a-z0-9_]*)/[A-Z]\w*", line)
            if match:
                refs.add(match.group(1))
    return refs


def test_dependencies_cover_every_referenced_package():
    from catkin_pkg.package import parse_package

    package = parse_package(str(msgcheck.MSGS / "package.xml"))
    depends = {d.name for d in package.build_depends} & {d.name for d in package.exec_depends}
    cmake = (msgcheck.MSGS / "CMakeLists.txt").read_text()
    cmake_deps = set(re.search(r"DEPENDENCIES([^)]*)\)", cmake).group(1).split())
    assert referenced_packages() <= depends
    assert referenced_packages() <= cmake_deps
    for dep in cmake_deps:
        assert f"find_package({dep} REQUIRED)" in cmake


def test_cmake_lists_exactly_the_interface_files():
    cmake = (msgcheck.MSGS / "CMakeLists.txt").read_text()
    listed = re.findall(r'"((?:msg|srv)/\w+\.(?:msg|srv))"', cmake)
    on_disk = sorted(
        str(p.relative_to(msgcheck.MSGS))
        for p in [*(msgcheck.MSGS / "msg").glob("*.msg"), *(msgcheck.MSGS / "srv").glob("*.srv")]
    )
    assert sorted(listed) == on_disk
    assert len(listed) == len(set(listed))
