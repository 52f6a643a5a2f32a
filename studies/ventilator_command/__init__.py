"""The ventilator study with its simulator run as an external program (a stand-in for a CAD batch run)."""
