"""The tests of the tools (tools/tests/meson.build runs them)."""
