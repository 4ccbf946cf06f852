# kick: `make run` and `make test` are the only set-up a user needs.
CARGO ?= cargo
STUDY ?= studies/dam_break.toml
OUT ?= reports
KICK = $(CARGO) run --release -q -p kick-study --

# .cargo/config.toml builds for x86-64-v3 (AVX2, FMA); older x86-64 CPUs get the baseline.
ifeq ($(shell uname -m),x86_64)
ifneq ($(shell grep -qw avx2 /proc/cpuinfo 2>/dev/null && grep -qw fma /proc/cpuinfo 2>/dev/null && echo yes),yes)
export RUSTFLAGS ?= -Ctarget-cpu=x86-64
endif
endif

.PHONY: run test build matrix bench fmt clean browser slurm-check findings-check

# The report's browser test needs Debian's chromium; install it when we can
# (root with apt). Without it the test fails, unless KICK_SKIP_BROWSER=1.
browser:
	@if command -v chromium >/dev/null 2>&1; then echo "chromium: $$(command -v chromium)"; \
	elif [ "$(KICK_SKIP_BROWSER)" = 1 ]; then echo "KICK_SKIP_BROWSER=1: the browser check is skipped"; \
	elif [ "$$(id -u)" = 0 ] && command -v apt-get >/dev/null 2>&1; then \
		echo "installing chromium for the report's browser test"; \
		DEBIAN_FRONTEND=noninteractive apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq chromium >/dev/null \
		|| { echo "chromium could not be installed (set KICK_SKIP_BROWSER=1 to skip the browser check)"; exit 1; }; \
	else echo "no chromium and no root apt: install chromium, or set KICK_SKIP_BROWSER=1 to skip the browser check"; exit 1; fi

build:
	$(CARGO) build --release -p kick-study

run: build
	$(KICK) run $(STUDY) --out $(OUT)
	$(KICK) report $(OUT)/$(basename $(notdir $(STUDY)))

test: browser
	$(CARGO) fmt --all -- --check
	$(CARGO) clippy --workspace --all-targets -- -D warnings
	$(CARGO) test --workspace

# Reruns a fixed sample of the findings' headline figures at 2 jobs and
# compares them with docs/findings/data/findings_check.json.
findings-check: build
	python3 scripts/findings_check.py --kick $(or $(CARGO_TARGET_DIR),target)/release/kick

matrix: build
	$(KICK) matrix studies/bug_report.toml --out $(OUT)/bug_report --resume $(MATRIX_ARGS)

bench: build
	$(KICK) bench --scene mpm88 --steps 2000 --threads 1
	$(KICK) bench --scene dam-break --steps 2000 --threads 1 --shape linear --transfer flip
	$(KICK) bench --scene dam-break --steps 2000 --threads 1 --shape bspline2 --transfer apic
	$(KICK) bench --scene dam-break --steps 2000 --threads 2 --shape bspline2 --transfer apic
	$(KICK) bench --scene dam-break --cell 0.0025 --steps 500 --threads 1 --shape bspline2 --transfer apic
	$(KICK) bench --scene dam-break --cell 0.0025 --steps 500 --threads 2 --shape bspline2 --transfer apic
	# The cost of each remedy on the modern baseline (quadratic B-spline, APIC).
	for r in method.force=mls method.f_reset=true method.cell_dilatation=true method.j_bar=true \
	         method.pressure_smoothing=true method.j_update=exp method.min_node_mass=true; do \
	  $(KICK) bench --scene dam-break --steps 2000 --threads 1 --shape bspline2 --transfer apic --set $$r; \
	done
	$(KICK) bench --scene dam-break --steps 2000 --threads 1 --shape bspline2 --transfer xpic --set method.xpic_order=5
	# The null-space filter (FLIP only) and cpGIMP, against the linear and uGIMP FLIP runs above and below.
	$(KICK) bench --scene dam-break --steps 2000 --threads 1 --shape linear --transfer flip --set method.null_space_filter=true
	$(KICK) bench --scene dam-break --steps 2000 --threads 1 --shape gimp --transfer flip
	$(KICK) bench --scene dam-break --steps 2000 --threads 1 --shape cpgimp --transfer flip
	# The pressure-implicit formulation's cost per particle-step.
	$(KICK) bench --scene dam-break --steps 2000 --threads 1 --shape bspline2 --transfer apic --set method.formulation=pressure_implicit

# A live check of `kick slurm` on a single-node SLURM cluster it brings up
# (root with apt; "skipped" otherwise). Not part of `make test`.
slurm-check: build
	scripts/slurm/check.sh $(or $(CARGO_TARGET_DIR),target)/release/kick

fmt:
	$(CARGO) fmt --all

clean:
	$(CARGO) clean
