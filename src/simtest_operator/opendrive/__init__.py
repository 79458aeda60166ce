"""OpenDRIVE road networks: parsing and geometry evaluation."""
