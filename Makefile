# Two commands a newcomer needs: `make demo` and `make test`. Both install what they need first.
# The catkin workspace lives in build/ws, with this repository linked in as build/ws/src/openable_ros.
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
	@[ -L $(WS)/src/openable_ros ] || ln -sfn $(CURDIR) $(WS)/src/openable_ros

build: deps workspace
	$(CATKIN_MAKE)

# Builds every test (gtest + rostest), runs them and prints catkin_test_results' summary.
# Exits non-zero when any test failed or did not run.
test: build
	$(CATKIN_MAKE) tests
	cd $(WS) && $(CATKIN_ENV) bash -c 'source devel/setup.bash && catkin_make run_tests -j1 -DPYTHON_EXECUTABLE=/usr/bin/python3 > $(CURDIR)/build/run_tests.log 2>&1; \
	  rc=$$?; grep -E "^\[ *(RUN|OK|FAILED|PASSED) *\]|FAILURE|Error" $(CURDIR)/build/run_tests.log | grep -vE "^\[ *(RUN|OK) *\]" | tail -n 60; \
	  catkin_test_results --verbose build/test_results > $(CURDIR)/build/test_results.txt; trc=$$?; \
	  grep -vE "^(Skipping|$$)" $(CURDIR)/build/test_results.txt | grep -E "failure|error|Summary|test" | tail -n 40; \
	  [ $$rc -eq 0 ] && [ $$trc -eq 0 ]'

demo: build
	@bash scripts/demo.sh $(WS)

bench: build
	@bash scripts/bench.sh $(WS)

clean:
	rm -rf build
