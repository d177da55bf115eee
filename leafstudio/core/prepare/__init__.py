"""Before step 1: the input made ready (outline, cloud, vein_order, units) and checked
(plausibility, cover); no step of the paper."""
