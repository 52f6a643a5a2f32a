"""The ventilator study at drawing resolution: its three lengths on a 0.1 mm grid."""
