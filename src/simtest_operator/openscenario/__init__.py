"""openscenario package."""
