# Thin wrapper giving the README's two commands:
#   make demo   the main job (today: predictions for the two paper scenes)
#   make test   the whole test suite: normal build, then ASan+UBSan build without the heavy tests
# Both first install missing Debian packages (as root) or print the exact command to run.

DEB_PACKAGES := cmake make gcc g++ pkg-config \
	libgsl-dev libinih-dev libsqlite3-dev libserialport-dev libmodbus-dev \
	libopencv-dev libmicrohttpd-dev libjansson-dev libcmocka-dev libcairo2-dev \
	libplplot-dev plplot-driver-cairo
JOBS ?= $(shell nproc 2>/dev/null || echo 2)
BUILD ?= build
ASAN_BUILD ?= build-asan

.PHONY: all deps build build-asan demo test test-normal test-asan clean

all: build

deps:
	@missing=""; \
	for p in $(DEB_PACKAGES); do \
	  dpkg-query -W -f='$${Status}' $$p 2>/dev/null | grep -q 'install ok installed' || missing="$$missing $$p"; \
	done; \
	if [ -n "$$missing" ]; then \
	  if [ "$$(id -u)" = 0 ]; then \
	    echo "installing Debian packages:$$missing"; \
	    apt-get update -q && DEBIAN_FRONTEND=noninteractive apt-get install -y -q --no-install-recommends $$missing; \
	  else \
	    echo "missing Debian packages; run this, then try again:"; \
	    echo "  sudo apt-get install -y --no-install-recommends$$missing"; \
	    exit 1; \
	  fi; \
	fi

build: deps
	cmake -S . -B $(BUILD) -DCMAKE_BUILD_TYPE=Release
	cmake --build $(BUILD) -j $(JOBS)

build-asan: deps
	cmake -S . -B $(ASAN_BUILD) -DCMAKE_BUILD_TYPE=Debug -DRIBBON_SANITIZE=ON
	cmake --build $(ASAN_BUILD) -j $(JOBS)

demo: build
	@for s in config/scenes/paper-gamma013.ini config/scenes/paper-gamma021.ini; do \
	  echo "== $$s"; ./$(BUILD)/bin/ribbon-sim predict --scene $$s --fast || exit 1; \
	done

test-normal: build
	cd $(BUILD) && ctest --output-on-failure -j $(JOBS)

test-asan: build-asan
	cd $(ASAN_BUILD) && ASAN_OPTIONS=detect_leaks=1 UBSAN_OPTIONS=print_stacktrace=1 \
	  ctest --output-on-failure -j $(JOBS) -LE heavy

test: test-normal test-asan

clean:
	rm -rf $(BUILD) $(ASAN_BUILD)
