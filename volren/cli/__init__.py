"""The `volren` command. It never imports Qt unless `volren view` runs."""
