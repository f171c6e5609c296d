# Set-up on a fresh machine: `make demo` and `make test` create .venv and install what they need.
PYTHON ?= $(shell command -v python3.11 || command -v python3)
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed

.PHONY: demo test bench clean browser

$(STAMP): pyproject.toml src/rotoprint/_native.c
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install -q --upgrade pip
	@echo "installing rotoprint, its C extension and its dependencies into $(VENV) (pip -q: quiet until done, 0.5-2 min)"
	$(BIN)/python -m pip install -q -e '.[test,bench]'
	@# numba caches its kernels in __pycache__ beside the sources: compile them now, in two
	@# processes, one line per kernel, instead of during the first demo / check / slice
	$(BIN)/python -m rotoprint._warmup
	touch $(STAMP)

demo: $(STAMP)
	$(BIN)/rotoprint demo --out demo-output

# The report test opens report.html in headless Chromium: Debian's chromium and chromium-driver.
SUDO := $(shell [ "$$(id -u)" = 0 ] || echo sudo)
browser:
	@if [ ! -x /usr/bin/chromium ] || [ ! -x /usr/bin/chromedriver ]; then \
	  echo "installing chromium and chromium-driver (Debian) for the report test"; \
	  $(SUDO) apt-get update -q && $(SUDO) env DEBIAN_FRONTEND=noninteractive apt-get install -y -q chromium chromium-driver; \
	fi

# two workers (CI's 2 cores); the tests that read the session's shared builds stay on one
# worker (xdist group "builds", tests/conftest.py). PYTEST_WORKERS=0 runs in one process.
PYTEST_WORKERS ?= 2
test: $(STAMP) browser
	$(BIN)/python -m pytest -q -n $(PYTEST_WORKERS) --dist loadgroup

bench: $(STAMP)
	$(BIN)/python bench/run.py

clean:
	rm -rf $(VENV) demo-output .pytest_cache build src/*.egg-info
	rm -f src/rotoprint/_native*.so
	find src -name '*.nbi' -delete -o -name '*.nbc' -delete
