"""The models of the family's papers: quarter car, road angle, standstill balance, corner loads."""
