# Two commands on a fresh machine with python3 and make:
#   make demo   — create .venv, install, run the main job on the embedded default data
#   make test   — create .venv, install, run the test suite (fast tests)
PYTHON ?= python3
VENV   ?= .venv
PY     := $(VENV)/bin/python
STAMP  := $(VENV)/.installed
OUT    ?= results

.PHONY: demo test test-install test-slow test-all bench clean default-data default-reference docs docs-pages

$(STAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -e '.[test]'
	touch $(STAMP)

demo: $(STAMP)
	$(VENV)/bin/translucency demo --out $(OUT) --overwrite

test: $(STAMP)
	$(VENV)/bin/ruff check src tests benchmarks docs/_gen && $(VENV)/bin/ruff format --check src tests benchmarks docs/_gen && $(PY) -m pytest -q -m "not slow" -n auto

# the documentation site (mkdocs-material, mkdocstrings) into build/site; --strict: every warning fails the
# build, a broken link or anchor among them; then the built site in headless Chromium with the network refused
# (tests/test_site_offline.py: formulas drawn, search answers, pictures load, nothing fetched from elsewhere)
DOCS_STAMP := $(VENV)/.docs-installed
$(DOCS_STAMP): $(STAMP)
	$(PY) -m pip install --quiet -e '.[docs]'
	touch $(DOCS_STAMP)

docs: $(DOCS_STAMP)
	NO_MKDOCS_2_WARNING=1 $(VENV)/bin/mkdocs build --strict --site-dir build/site
	TRANSLUCENCY_SITE=build/site $(PY) -m pytest -q -p no:cacheprovider tests/test_site_offline.py

# the generated pages, rewritten from the commands and the schemas of --json (docs/_gen: generators, not
# part of the package); tests/test_docs_site.py, test_commands.py and test_json.py hold them current
docs-pages: $(STAMP)
	$(PY) docs/_gen/cli_reference.py > docs/reference/cli.md
	$(PY) docs/_gen/cli_reference.py --api docs/api.md
	$(PY) docs/_gen/json_schemas.py > docs/json.md

# the README's install and first-result lines, as written, in a fresh virtual environment (pip downloads)
test-install: $(STAMP)
	$(PY) -m pytest -q -m install tests/test_install.py

test-slow: $(STAMP)
	$(PY) -m pytest -q -m slow
	TRANSLUCENCY_HYPOTHESIS_PROFILE=long $(PY) -m pytest -q tests/test_fuzz.py

test-all: $(STAMP)
	$(PY) -m pytest -q

bench: $(STAMP)
	$(PY) benchmarks/model_size.py
	$(PY) benchmarks/photon_transport.py
	$(PY) benchmarks/tally_vs_volpath.py
	$(PY) benchmarks/fit_speed.py
	$(PY) benchmarks/render_speed.py
	$(PY) benchmarks/startup.py

clean:
	rm -rf $(VENV) $(OUT) .pytest_cache .hypothesis

# the embedded default data: the fitted scan, its held-out truth and the fine near-x_i profiles of Figure 1
# (marble with a fibrous band, translucency.pipeline.write_default_data; about 10 minutes on 2 quiet cores)
default-data: $(STAMP)
	$(PY) -c "from translucency.pipeline import write_default_data as w; print(w())"

# the converged volpath reference of Figure 2 (2 x 256 samples per pixel, about 10 minutes on 2 cores)
default-reference: $(STAMP)
	$(PY) -c "from translucency.pipeline import write_figure2_reference as w; print(w())"
