"""The occupant models held against real region outcomes (NASS-CDS 1997-2014; issue 39)."""
