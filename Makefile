# kick: `make run` and `make test` are the only set-up a user needs.
CARGO ?= cargo
STUDY ?= studies/dam_break.toml
OUT ?= reports
KICK = $(CARGO) run --release -q -p kick-study --

.PHONY: run test build matrix bench fmt clean

build:
	$(CARGO) build --release -p kick-study

run: build
	$(KICK) run $(STUDY) --out $(OUT)

test:
	$(CARGO) fmt --all -- --check
	$(CARGO) clippy --workspace --all-targets -- -D warnings
	$(CARGO) test --workspace

matrix: build
	$(KICK) matrix studies/bug_report.toml --out $(OUT)/bug_report --resume $(MATRIX_ARGS)

bench: build
	$(KICK) bench --scene mpm88 --steps 2000 --threads 1
	$(KICK) bench --scene dam-break --steps 2000 --threads 1 --shape linear --transfer flip
	$(KICK) bench --scene dam-break --steps 2000 --threads 1 --shape bspline2 --transfer apic
	$(KICK) bench --scene dam-break --steps 2000 --threads 2 --shape bspline2 --transfer apic

fmt:
	$(CARGO) fmt --all

clean:
	$(CARGO) clean
