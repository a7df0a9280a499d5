"""pytest plugin entry point (hooks only). Filled in by the plugin work (issue 3)."""
