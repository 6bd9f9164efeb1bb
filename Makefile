# make demo : generate the sample audio book from samples/ into out/demo/
# make test : lint (ruff), type-check (mypy), then run the test suite
# make bench: print speed / size / accuracy figures (see docs/BENCHMARKS.md)
# Each target sets up .venv (and Debian packages, as root) first when needed.

PY := .venv/bin/python
STAMP := .venv/.installed

.PHONY: demo test bench setup clean

$(STAMP): pyproject.toml scripts/setup.sh
	bash scripts/setup.sh
	touch $@

setup: $(STAMP)

demo: $(STAMP)
	$(PY) -m cartoonface.demo

test: $(STAMP)
	.venv/bin/ruff check .
	.venv/bin/mypy
	$(PY) -m pytest -q

bench: $(STAMP)
	$(PY) -m bench

clean:
	rm -rf out .pytest_cache
