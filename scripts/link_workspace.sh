#!/usr/bin/env bash
# Makes build/ws/src/openable_ros a folder of links to the repository's top-level entries, except build/.
#
# A single link to the repository root would put build/ws/src/openable_ros/build/ws/src/openable_ros/...
# under the package: roslaunch walks the package folder following links (to find node executables) and
# never comes back from that cycle. Linking the entries one by one keeps build/ out of the package.
set -euo pipefail
pkg=${1:?usage: link_workspace.sh PACKAGE_FOLDER_IN_WORKSPACE}
root=$(cd "$(dirname "$0")/.." && pwd)
[ -L "$pkg" ] && rm "$pkg"
mkdir -p "$pkg"
find "$pkg" -maxdepth 1 -type l ! -exec test -e {} \; -delete  # entries removed from the repository
for entry in "$root"/*; do
  name=$(basename "$entry")
  [ "$name" = build ] && continue
  ln -sfn "$entry" "$pkg/$name"
done
