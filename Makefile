# anklelab developer commands. Every target creates and updates .venv on demand, so a fresh
# machine with only Python 3.11 and pip can run `make demo` or `make test` directly.
PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed

.PHONY: demo test lint typecheck bench browser clean numba-cache

# numba's on-disk cache checks only the timestamp of a kernel's own file, not of the callees it
# inlines from other files; so the cache lives in a directory named after a hash of every file
# that holds or feeds a kernel, and a change to any of them starts a fresh cache.
KERNEL_SOURCES := $(sort $(wildcard src/anklelab/sim/*.py src/anklelab/sim/*/*.py \
  src/anklelab/control/*.py src/anklelab/experiments/_*.py) \
  $(shell grep -rl --include='*.py' numba src/anklelab))
KERNEL_HASH := $(shell cat $(KERNEL_SOURCES) | sha1sum | cut -c1-12)
NUMBA_CACHE := $(CURDIR)/.numba_cache/$(KERNEL_HASH)

$(STAMP): pyproject.toml
	test -x $(BIN)/python || $(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -e ".[dev]"
	touch $(STAMP)

demo: $(STAMP)
	$(BIN)/anklelab demo --force

lint: $(STAMP)
	$(BIN)/ruff check .
	$(BIN)/ruff format --check .

# not part of `make test`: a newer mypy or NumPy's stubs may find new things to say
typecheck: $(STAMP)
	$(BIN)/mypy src

# The report tests open pages in Debian's headless Chromium; install it when missing (as root).
browser:
	@test -x /usr/bin/chromium || { [ "$$(id -u)" = 0 ] && \
	  { apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq chromium >/dev/null; }; } || \
	  echo "warning: chromium is not installed; browser tests will be skipped (failed on CI)"

# drop the caches of older kernel sources
numba-cache:
	@mkdir -p $(NUMBA_CACHE)
	@find .numba_cache -mindepth 1 -maxdepth 1 ! -name $(KERNEL_HASH) -exec rm -rf {} +

test: lint browser numba-cache
	NUMBA_CACHE_DIR=$(NUMBA_CACHE) $(BIN)/python -m pytest -q

bench: $(STAMP) numba-cache
	NUMBA_CACHE_DIR=$(NUMBA_CACHE) $(BIN)/python -m benchmarks

clean:
	rm -rf $(VENV) .numba_cache .pytest_cache build *.egg-info src/*.egg-info
