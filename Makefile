# server_select: `make demo` runs the main job on one host, `make test` runs every test.
# Everything needed is installed on first use (Debian packages, then a venv for pip packages).

SHELL := /bin/bash
TOP := $(CURDIR)
BUILD := $(TOP)/build
DEVEL := $(BUILD)/devel
VENV := $(TOP)/.venv
PY := $(VENV)/bin/python
APT_PACKAGES := $(shell grep -v '^\#' $(TOP)/debian-packages.txt)
DEMO_DURATION ?= 30
# the loopback demo's summary, printed again once roslaunch's shutdown lines are done
DEMO_MD := $(BUILD)/demo_summary.md
# Runs a command with the workspace sourced and the venv's python first on PATH (the
# scripts' `#!/usr/bin/env python3` must find the interpreter that sees rospy).
ROSENV := source $(DEVEL)/setup.bash && export PATH=$(VENV)/bin:$$PATH ROS_HOME=$(BUILD)/ros_home &&

.PHONY: all deps build demo demo-loopback search-demo evaluate evaluate-suite bench bench-emulator bench-memory bench-loopback \
  bench-scale bench-routing bench-hedging bench-capacity league calibrate league-testbed soak bench-master bench-fleet bench-seal bench-probes bench-top bench-robot \
  test check unit-test testbed-test fault-test catkin-test rostest lint docs help clean
all: build

help:
	@echo 'make demo            the main job: the testbed experiment (root, TUN) or the loopback demo'
	@echo 'make test            every test (lint, unit, testbed, bench smoke, faults, catkin workspace)'
	@echo 'make check           lint and unit tests: no build, no master (15 s)'
	@echo 'make build           Debian packages, the venv, the devel space in build/devel'
	@echo 'make demo-loopback   manager + 3 servers + 2 robots on this host (DEMO_DURATION, DEMO_PORT)'
	@echo 'make search-demo     the cooperative search: 2 robots, 2 servers, hidden people'
	@echo 'make evaluate        the paper experiment on the testbed (SCENARIO=config/...yaml)'
	@echo 'make evaluate-suite  every scenario, every variant, side by side (about 45 min)'
	@echo 'make league          the fleet profile beside the peer balancers, simulated (~4 min)'
	@echo 'make calibrate       the simulator beside the testbed league (~4 min)'
	@echo 'make league-testbed  the league on the testbed, for cells named in LEAGUE_ARGS'
	@echo 'make soak            the fleet through every fault kind for SOAK_MINUTES (root, TUN)'
	@echo 'make bench           the papers tables and throughput (bench-scale, bench-routing,'
	@echo '                     bench-hedging, bench-capacity, bench-master, bench-memory, bench-emulator,'
	@echo '                     bench-seal, bench-probes, bench-fleet, bench-top, bench-robot)'
	@echo 'make unit-test, testbed-test, fault-test, catkin-test, rostest T=x.test, lint: parts of make test'
	@echo 'make docs            docs/parameters.md from the parameter table and the launch files'
	@echo 'make clean           remove build/ and .venv'

# docs/parameters.md, made from the parameter table and the launch files (make test checks it).
docs: deps
	@cd $(TOP)/src && env -u PYTHONPATH ROS_PACKAGE_PATH=$(TOP) $(PY) -m server_select.paramdoc --write

$(BUILD)/.apt-stamp: debian-packages.txt
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
	$(VENV)/bin/pip install --disable-pip-version-check -q --ignore-installed -r requirements.txt
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

# With root and TUN: a short version of the evaluation (3 modes on config/demo_short.yaml,
# about 2 minutes). Otherwise: the loopback demo (all nodes on this host, DEMO_DURATION s).
demo: build
	@$(ROSENV) cd $(TOP) && if $(PY) -c 'import sys; from server_select.testbed.netns import available; \
	    ok, why = available(); print("" if ok else why); sys.exit(0 if ok else 1)'; then \
	  echo "demo: testbed experiment on config/demo_short.yaml (select, fixed, oracle, and the fleet profile; ~3 min)"; \
	  $(PY) scripts/evaluate --scenario config/demo_short.yaml --modes select,fixed,oracle,fleet \
	    --out $(BUILD)/demo_eval; \
	else \
	  echo "demo: the testbed is not available here (see above): running the loopback demo"; \
	  echo "demo: manager + 3 servers + 2 robots on this host for $(DEMO_DURATION) s"; \
	  export ROS_MASTER_URI=http://localhost:$${DEMO_PORT:-11411} && rm -f $(DEMO_MD) && \
	  roslaunch --port $${DEMO_PORT:-11411} server_select demo.launch \
	    duration:=$(DEMO_DURATION) output:=log summary_file:=$(BUILD)/demo_summary.json; \
	  status=$$?; [ ! -f $(DEMO_MD) ] || cat $(DEMO_MD); exit $$status; \
	fi

# The loopback demo even where the testbed is available.
demo-loopback: build
	@$(ROSENV) export ROS_MASTER_URI=http://localhost:$${DEMO_PORT:-11411} && rm -f $(DEMO_MD) && \
	  roslaunch --port $${DEMO_PORT:-11411} server_select demo.launch \
	    duration:=$(DEMO_DURATION) output:=log summary_file:=$(BUILD)/demo_summary.json; \
	  status=$$?; [ ! -f $(DEMO_MD) ] || cat $(DEMO_MD); exit $$status

# Cooperative search: 2 robots, 2 servers, people hidden in a synthetic area; ends when all
# are found and prints who found what and when.
search-demo: build
	@$(ROSENV) export ROS_MASTER_URI=http://localhost:$${DEMO_PORT:-11412} && \
	  roslaunch --port $${DEMO_PORT:-11412} server_select search_demo.launch \
	    summary_file:=$(BUILD)/search_summary.json

# The paper's experiment on the testbed (root): 3 modes x 160 s, bags + report + plots.
SCENARIO ?= config/paper_moving.yaml
evaluate: build
	@$(ROSENV) cd $(TOP) && $(PY) scripts/evaluate --scenario $(SCENARIO) --out results/eval

# Every selection variant side by side on the scenario suite, 3 runs each: results/suite.
evaluate-suite: build
	@$(ROSENV) cd $(TOP) && $(PY) scripts/evaluate --suite --out results/suite

# The second paper's tables and throughput: results/bench/*.json and REPORT.md.
bench: build
	@$(ROSENV) cd $(TOP) && $(PY) -m server_select.bench.run --out results/bench

# RSS of every demo node over 10 minutes at 20 sort tasks/s per robot.
bench-memory: build
	@$(ROSENV) cd $(TOP) && $(PY) -m server_select.bench.memory --out results/bench

# The manager against simulated robots, per pair and per robot, 2x3 to 500x100 (~12 min).
bench-scale: build
	@$(ROSENV) cd $(TOP) && $(PY) -m server_select.bench.scale --out results/bench

# Bytes per task on the testbed, broadcast vs direct routing, 2-8 servers (root, ~8 min).
bench-routing: build
	@$(ROSENV) cd $(TOP) && $(PY) -m server_select.bench.routing_bytes --out results/bench

# Hedged tasks on lossy links, off vs on: tail round trip and extra requests (root, ~6 min).
bench-hedging: build
	@$(ROSENV) cd $(TOP) && $(PY) -m server_select.bench.hedging --out results/bench

# Goodput and round trip against offered load on servers of finite CPU (cgroup quotas):
# paper, fleet and the static assignment; overload, crowd and herd (root, ~50 min).
# The league, simulated: the fleet profile beside the peers (p2c peak-EWMA, least request,
# Prequal, weighted round robin, replication) on every network scenario and capacity case,
# 30 paired seeds each (the package's own core objects on a virtual clock; ~4 min).
# Tables and plot: results/league/league.md (docs/league.md). LEAGUE_ARGS: e.g. "--seeds 60"
# or "--scenarios gen:1-200".
LEAGUE_ARGS ?=
league: build
	@$(ROSENV) cd $(TOP) && $(PY) -m server_select.sim.league --out results/league $(LEAGUE_ARGS)

# The simulator beside the testbed league's medians (config/sim/testbed.yaml; ~4 min).
calibrate: build
	@$(ROSENV) cd $(TOP) && $(PY) -m server_select.sim.calibration --out results/league

# The league on the testbed, to confirm cells the simulated league names (root, TUN; all
# cells about 2.5 hours): e.g. LEAGUE_ARGS="--part network --scenarios crossing
# --variants oracle_fleet,fleet,prequal".
league-testbed: build
	@$(ROSENV) cd $(TOP) && $(PY) -m server_select.bench.league --out results/league_testbed \
	  $(LEAGUE_ARGS)

bench-capacity: build
	@$(ROSENV) cd $(TOP) && for s in overload crowd herd; do \
	  $(PY) -m server_select.bench.capacity --scenario $$s --repeats 2 --out results/bench \
	  || exit 1; done

# Probe calls per robot per second and robot CPU, uniform vs adaptive probing, 10, 50 and
# 100 servers, 3 runs each (~8 min).
bench-probes: build
	@$(ROSENV) cd $(TOP) && $(PY) -m server_select.bench.probe_cost --out results/bench

# Calls to the master per node in steady state, both profiles, through a counting proxy
# (20 robots, 5 servers, the manager on this host; ~4 min).
bench-master: build
	@$(ROSENV) cd $(TOP) && $(PY) -m server_select.bench.master_calls --out results/bench

# A fleet of real nodes on this host (10x5, 30x10, 60x15), every probe sample to the
# manager vs robots' own rankings: CPU and RSS per role, bytes in and flag bytes (~12 min).
bench-fleet: build
	@$(ROSENV) cd $(TOP) && $(PY) -m server_select.bench.fleet_nodes --out results/bench

# Signed fleet messages: us to seal and check a flag, a batch, a result (no master); then
# node CPU and RSS with and without a key, two fleets side by side, 3 runs (~6 min).
bench-seal: build
	@$(ROSENV) cd $(TOP) && $(PY) -m server_select.bench.seal_cost --out results/bench \
	  && $(PY) -m server_select.bench.seal_fleet --out results/bench

# The live view's cost: top's CPU and RSS beside a fleet of 20 robots x 10 servers, 3 runs
# (~6 min).
bench-top: build
	@$(ROSENV) cd $(TOP) && $(PY) -m server_select.bench.top_cost --out results/bench

# The fleet demo on one host, 3 runs of 90 s: switches a minute per robot, each move's
# margin, the spread of the work servers report (what sim.work_noise fits; ~5 min).
bench-loopback: build
	@$(ROSENV) cd $(TOP) && $(PY) -m server_select.bench.loopback_demo --out results/bench

# A robot node's CPU and RSS by profile, servers (4, 10, 30) and workload (sort tasks,
# a compressed camera), here and on an emulated Raspberry Pi 3 (root), 3 runs, and where
# its time goes (py-spy; ~25 min).
bench-robot: build
	@$(ROSENV) cd $(TOP) && $(PY) -m server_select.bench.robot_cost --profile 30 --out results/bench

# Link emulator accuracy: configured vs measured round trip (root).
bench-emulator: build
	@$(ROSENV) cd $(TOP) && $(PY) -m server_select.bench.emulator --out results/bench

# The chaos soak (root, TUN): the keyed fleet on the testbed through a seeded schedule of
# every fault kind (at least twice each), SOAK_MINUTES long; invariants, recovery and
# resource slopes from the bags: results/soak/report.md and timeline.png. SOAK_KINDS: only
# these kinds (e.g. overload,server_kill), as many of each as fit.
SOAK_MINUTES ?= 30
SOAK_SEED ?= 1
SOAK_KINDS ?=
soak: build
	@$(ROSENV) cd $(TOP) && $(PY) -m server_select.soak.run --minutes $(SOAK_MINUTES) \
	  --seed $(SOAK_SEED) $(if $(SOAK_KINDS),--kinds $(SOAK_KINDS)) --out results/soak

unit-test: build
	@$(ROSENV) cd $(TOP) && $(PY) -m pytest -q test/unit test/ros

# One rostest file: make rostest T=manager.test (default: all of them)
rostest: build
	@$(ROSENV) cd $(TOP) && bash test/run_rostests.sh $(T)

# catkin_lint for the package, flake8 (Debian's, settings in setup.cfg) for the Python.
LINT := catkin_lint -W2 --strict --ignore package_path_name $(TOP) $(TOP)/examples/wordcount_task && \
  /usr/bin/python3 -m flake8 src test examples $(filter-out %.sh,$(wildcard scripts/*))
lint: deps
	@cd $(TOP) && $(LINT)

# The quick check while working: lint and the unit tests, with no build and no master
# (the ROS-free layers need neither; package files are found on ROS_PACKAGE_PATH).
check: deps
	@cd $(TOP) && $(LINT) && env -u PYTHONPATH ROS_PACKAGE_PATH=$(TOP) \
	  $(PY) -m pytest -q -p no:cacheprovider test/unit

# Lint first. Then three streams at once (test/alongside.sh; each mostly waits for nodes,
# messages and windows: a make test kept this host's 2 cores 63 % busy), after the tests of
# CPU limits (QUIET_TESTS: they need no other work beside them). At the lowest priority:
# the package in a fresh catkin workspace (`catkin_make run_tests` runs every launch-level
# rostest once, then the demo and a bag), then one tiny run of every benchmark (beside the
# catkin stage, a fourth stream, they overloaded the 2 cores: timing tests failed in 3 runs
# of 4; two at a time, after it). At normal priority, each in a scheduling group of its
# own: the fault tests (three pytest workers, each with a roscore of its own and whole
# files; real signals; they print their counts), then the unit tests, the ROS-side tests that need the build but no master
# and the longest benchmark runs; and in the foreground the testbed tests (root and TUN;
# reported as skipped elsewhere). The streams held back print when the foreground is done;
# the slowest tests are listed.
test: build
	@$(ROSENV) cd $(TOP) && $(LINT) && bash test/alongside.sh \
	  'bash test/catkin_workspace.sh; c=$$?; $(PY) -m pytest -q -rs -n 2 --durations=5 \
	    test/bench --ignore=$(BENCH_LAST) && exit $$c' \
	  bash -c '$(PY) -m pytest -q -rs $(QUIET_TESTS); quiet=$$?; bash test/alongside.sh --nice 0 \
	    "$(FAULT_TEST); f=\$$?; $(PY) -m pytest -q -rs --durations=10 test/unit test/ros \
	      $(BENCH_LAST) && exit \$$f" \
	    bash -c "$(PY) -m pytest -q -rs --durations=20 --ignore=$(QUIET_TESTS) test/testbed" \
	    && exit $$quiet'
# Tests that measure this machine's CPU: first, while only the lowest priority runs beside.
QUIET_TESTS := test/testbed/test_cpu_limit.py
# The longest benchmark smoke runs: after the fault, unit and ros tests, which end before
# the testbed tests (the longest stream).
BENCH_LAST := test/bench/test_bench_reports.py

# The package in a fresh catkin workspace with Debian's packages only: catkin_make,
# catkin_make run_tests, the timed demo.
catkin-test: deps
	@bash test/catkin_workspace.sh

# Servers killed and stopped, manager and roscore killed, forged input: counts printed
# (-rP: each test's output after the run). Three worker processes (pytest-xdist), whole
# files each: a worker is a ROS node of the roscore it starts.
FAULT_TEST := $(PY) -m pytest -q -rsP -n 3 --dist loadfile -p no:logging \
  -W ignore::DeprecationWarning --durations=10 test/fault
fault-test: build
	@$(ROSENV) cd $(TOP) && $(FAULT_TEST)

testbed-test: build
	@$(ROSENV) cd $(TOP) && $(PY) -m pytest -q -rs test/testbed

clean:
	rm -rf $(BUILD) $(VENV)
