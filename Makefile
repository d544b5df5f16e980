PYTHON ?= python3.11
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed

.PHONY: demo test bench lint clean

$(STAMP): pyproject.toml
	@command -v $(PYTHON) >/dev/null 2>&1 || { echo "$(PYTHON) not found; set PYTHON=..."; exit 2; }
	test -d $(VENV) || $(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	PYTHONWARNINGS="ignore:Editable installation" $(BIN)/python -m pip install --quiet -e ".[dev]"
	touch $(STAMP)

demo: $(STAMP)
	$(BIN)/graphvision run pipelines/homography.yaml --output-dir out/homography
	@echo "results and report in out/homography (open out/homography/report.html in a browser)"

test: $(STAMP)
	@start=$$(date +%s); $(BIN)/python -m pytest -n 2 --dist worksteal; status=$$?; \
	echo "make test: $$(( $$(date +%s) - start )) s"; exit $$status

lint: $(STAMP)
	$(BIN)/ruff check graphvision plugins tests bench
	$(BIN)/ruff format --check graphvision plugins tests bench
	$(BIN)/mypy
	$(BIN)/lint-imports

# OpenCV 5 moved the cascade classifier, HOG and ximgproc to opencv-contrib, which cannot
# share an environment with opencv-python-headless: it goes in a folder of its own (cv2
# only, the venv's numpy), which the contrib rows load in a child process.
CONTRIB := $(VENV)/opencv-contrib

bench: $(STAMP)
	$(BIN)/python -m pip install --quiet -e ".[dev,bench]"
	test -d $(CONTRIB)/cv2 || $(BIN)/python -m pip install --quiet --no-deps --target $(CONTRIB) opencv-contrib-python-headless
	GRAPHVISION_OPENCV_CONTRIB=$(abspath $(CONTRIB)) $(BIN)/python bench/run_all.py

# The site is built from real runs: every pipeline runs (values cached in
# .graphvision-cache/docs, so a second build takes a fraction of the first).
.PHONY: docs
docs: $(STAMP)
	$(BIN)/python -m pip install --quiet -e ".[dev,docs]"
	NO_MKDOCS_2_WARNING=1 DISABLE_MKDOCS_2_WARNING=true $(BIN)/mkdocs build --strict
	@echo "site in site/ (open site/index.html in a browser)"

clean:
	rm -rf $(VENV) out .graphvision-cache
