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
	@echo "the matrix runner arrives with the study-runner issue; running each case in turn"
	for c in $$($(KICK) list studies/bug_report.toml | cut -f1); do \
		$(KICK) run studies/bug_report.toml --case $$c --out $(OUT)/bug_report || exit $$?; \
	done

bench: build
	$(KICK) bench --scene mpm88 --steps 2000 --threads 1
	$(KICK) bench --scene dam-break --steps 2000 --threads 1 --shape linear --transfer flip
	$(KICK) bench --scene dam-break --steps 2000 --threads 1 --shape bspline2 --transfer apic
	$(KICK) bench --scene dam-break --steps 2000 --threads 2 --shape bspline2 --transfer apic

fmt:
	$(CARGO) fmt --all

clean:
	$(CARGO) clean
