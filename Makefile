# server_select: `make demo` runs the main job on one host, `make test` runs every test.
# Everything needed is installed on first use (Debian packages, then a venv for pip packages).

SHELL := /bin/bash
TOP := $(CURDIR)
BUILD := $(TOP)/build
DEVEL := $(BUILD)/devel
VENV := $(TOP)/.venv
PY := $(VENV)/bin/python
APT_PACKAGES := python3-venv python3-rospy python3-rostest python3-roslaunch python3-rosbag \
  python3-rosservice python3-rostopic python3-rosnode python3-rosmsg python3-roslib \
  catkin catkin-lint ros-message-generation libstd-msgs-dev libsensor-msgs-dev ros-base-dev \
  rosbash procps cmake g++ make iproute2
DEMO_DURATION ?= 30
# Runs a command with the workspace sourced and the venv's python first on PATH (the
# scripts' `#!/usr/bin/env python3` must find the interpreter that sees rospy).
ROSENV := source $(DEVEL)/setup.bash && export PATH=$(VENV)/bin:$$PATH ROS_HOME=$(BUILD)/ros_home &&

.PHONY: all deps build demo test unit-test rostest lint clean
all: build

$(BUILD)/.apt-stamp:
	@mkdir -p $(BUILD)
	@missing=$$(for p in $(APT_PACKAGES); do dpkg-query -W -f='$${Status}\n' $$p 2>/dev/null \
	    | grep -q 'install ok installed' || echo $$p; done); \
	if [ -n "$$missing" ]; then \
	  echo "installing Debian packages: $$missing"; \
	  SUDO=$$( [ "$$(id -u)" = 0 ] || echo sudo ); \
	  $$SUDO apt-get update && DEBIAN_FRONTEND=noninteractive $$SUDO apt-get install -y \
	    --no-install-recommends $$missing; \
	fi
	@touch $@

$(VENV)/.stamp: requirements.txt $(BUILD)/.apt-stamp
	/usr/bin/python3 -m venv --system-site-packages $(VENV)
	$(VENV)/bin/pip install --disable-pip-version-check -q -r requirements.txt
	@touch $@

deps: $(BUILD)/.apt-stamp $(VENV)/.stamp

# A single catkin package builds standalone with CMake: devel space in build/devel, and the
# source tree itself on ROS_PACKAGE_PATH (no workspace symlink for roslaunch to recurse into).
build: deps
	@mkdir -p $(BUILD)/cmake
	cd $(BUILD)/cmake && cmake $(TOP) -DCATKIN_DEVEL_PREFIX=$(DEVEL) -DPYTHON_EXECUTABLE=$(PY) \
	  -DCATKIN_ENABLE_TESTING=OFF -DCMAKE_BUILD_TYPE=Release > $(BUILD)/cmake.log 2>&1 \
	  && $(MAKE) -C $(BUILD)/cmake >> $(BUILD)/cmake.log 2>&1 \
	  || { tail -40 $(BUILD)/cmake.log; exit 1; }
	@echo "built devel space $(DEVEL) (log: $(BUILD)/cmake.log)"

demo: build
	@echo "demo: manager + 3 servers + 2 robots on this host for $(DEMO_DURATION) s"
	@$(ROSENV) export ROS_MASTER_URI=http://localhost:$${DEMO_PORT:-11411} && \
	  roslaunch --port $${DEMO_PORT:-11411} server_select demo.launch \
	    duration:=$(DEMO_DURATION) output:=log summary_file:=$(BUILD)/demo_summary.json

unit-test: build
	@$(ROSENV) cd $(TOP) && $(PY) -m pytest -q test/unit

# One rostest file: make rostest T=manager.test (default: all of them)
rostest: build
	@$(ROSENV) cd $(TOP) && bash test/run_rostests.sh $(T)

lint: build
	@$(ROSENV) catkin_lint -W2 --strict --ignore package_path_name $(TOP)

# Lint first, then unit tests (no master), then the launch-level rostests; the last line
# printed is the rostest tally "rostest: N passed, N failed".
test: build
	@$(ROSENV) cd $(TOP) && catkin_lint -W2 --strict --ignore package_path_name $(TOP) \
	  && $(PY) -m pytest -q test/unit && bash test/run_rostests.sh

clean:
	rm -rf $(BUILD) $(VENV)
