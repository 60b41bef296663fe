#!/usr/bin/env python3
"""The core is ROS-free: fails when any header outside what the core may use reached a core object file.

    scripts/check_core_ros_free.py CATKIN_WORKSPACE

On Debian, ROS's headers live in /usr/include beside the C++ library's, so no include path can keep them out
of the core: this check reads what the compiler itself recorded (CMake's compiler_depend.make of the targets
openable_core and openable_pose_graph, written at build time) and allows only the C library, the C++ library,
OpenCV, yaml-cpp, Eigen, Ceres (pose graph) and the package's own include/openable and src/core. Anything
else (ros/, sensor_msgs/, the generated openable_ros/ messages, include/openable_ros/) is named with the
object that included it. Exits 0 when clean, 1 otherwise.
"""
import os
import re
import sys

CORE_TARGETS = ("openable_core", "openable_pose_graph")
# Folders of /usr/include the core may reach (headers directly in /usr/include are the C library's).
ALLOWED_SYSTEM = ("c++", "x86_64-linux-gnu", "aarch64-linux-gnu", "linux", "asm-generic", "asm", "sys", "bits",
                  "opencv4", "yaml-cpp", "eigen3", "ceres", "glog", "gflags")


def allowed(header, package):
    if header.startswith("/usr/lib/gcc"):
        return True
    if header.startswith("/usr/include/"):
        rest = header[len("/usr/include/"):]
        return "/" not in rest or rest.split("/", 1)[0] in ALLOWED_SYSTEM
    real = os.path.realpath(header)
    return any(real.startswith(os.path.join(package, inside) + "/") for inside in ("include/openable", "src/core"))


def main():
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    workspace = sys.argv[1]
    package = os.path.realpath(os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
    checked, bad = 0, []
    for target in CORE_TARGETS:
        depend = os.path.join(workspace, "build", "openable_ros", "CMakeFiles", target + ".dir", "compiler_depend.make")
        if not os.path.isfile(depend):
            print(f"no {depend}: build the workspace first")
            return 1
        obj = None
        for line in open(depend):
            rule = re.match(r"^(\S+\.o):", line)
            if rule:
                obj = rule.group(1)
                line = line[rule.end():]
            for header in re.findall(r"(/\S+\.(?:h|hpp|hh|hxx|inl)|/\S+/c\+\+/\S+)", line):
                checked += 1
                if not allowed(header, package):
                    bad.append((obj, header))
    for obj, header in bad[:40]:
        print(f"core object {obj} includes {header}: not a header the ROS-free core may use")
    print(f"core_ros_free: {checked} header references of {', '.join(CORE_TARGETS)} checked, {len(bad)} not allowed")
    return 1 if bad or checked == 0 else 0


if __name__ == "__main__":
    sys.exit(main())
