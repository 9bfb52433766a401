"""Contact: rigid level-set obstacles, contact surfaces and pairs, the level-set
(Signorini–Moreau) contact model and its Signorini baseline, Coulomb friction, the records of a
contact history and the compiled projection kernel."""
