# Two commands a newcomer needs: `make demo` and `make test`. Both install what they need first.
# The catkin workspace lives in build/ws; build/ws/src/openable_ros links to this repository's files.
SHELL := /bin/bash
WS := $(CURDIR)/build/ws
JOBS ?= $(shell nproc)
# Debian's catkin needs Debian's python3, not whatever python3 comes first on PATH.
CATKIN_ENV := PATH=/usr/bin:/bin:$$PATH ROS_HOME=$(CURDIR)/build/ros_home ROS_LOG_DIR=$(CURDIR)/build/ros_home/log
CATKIN_MAKE := cd $(WS) && $(CATKIN_ENV) catkin_make -DCMAKE_BUILD_TYPE=Release -DPYTHON_EXECUTABLE=/usr/bin/python3 \
	-DCATKIN_ENABLE_TESTING=ON -j$(JOBS)

.PHONY: all deps workspace build test demo bench clean

all: build

deps:
	@bash scripts/install_deps.sh

workspace:
	@mkdir -p $(WS)/src build/ros_home
	@bash scripts/link_workspace.sh $(WS)/src/openable_ros

build: deps workspace
	$(CATKIN_MAKE)

# Builds every test (gtest + rostest), runs them, prints the summary; non-zero exit when anything failed.
test: build
	$(CATKIN_MAKE) tests
	@bash scripts/run_tests.sh $(WS)

demo: build
	@bash scripts/demo.sh $(WS)

bench: build
	@bash scripts/bench.sh $(WS)

# Fuzzes the loaders of untrusted files (map, configuration YAML, .npy) with libFuzzer, ASan and UBSan,
# FUZZ_SECONDS each. Needs clang (an optional package of deps; make test runs the same script for 10 s a target).
FUZZ_SECONDS ?= 60
.PHONY: fuzz
fuzz: deps
	@dpkg-query -W -f='$${Status}' clang 2>/dev/null | grep -q "install ok installed" || { \
	  SUDO=""; [ "$$(id -u)" -eq 0 ] || SUDO=sudo; \
	  $$SUDO apt-get update -qq && DEBIAN_FRONTEND=noninteractive $$SUDO apt-get install -y -qq --no-install-recommends clang >/dev/null; }
	@FUZZ_SECONDS=$(FUZZ_SECONDS) JOBS=$(JOBS) bash test/fuzz/run_fuzz.sh

# Memory of LoopDetector over 100,000 frames, unbounded and with max_history 10,000 (doc/performance.md).
.PHONY: soak
soak: build
	$(WS)/devel/lib/openable_ros/openable_soak --max-history 0
	$(WS)/devel/lib/openable_ros/openable_soak --max-history 10000

# The nodes themselves over ROS: MonoDetector and PlaceServer, 100,000 frames, max_history 10,000, a private
# roscore (scripts/node_soak.sh; README "Soak of the nodes"). A few minutes; not part of make test.
.PHONY: node_soak
node_soak: build
	@bash scripts/node_soak.sh $(WS)

clean:
	rm -rf build
