"""The public kiosk: a web page and a small JSON API that submit characters over the bus."""
