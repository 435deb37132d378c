"""The diagnosis: the residual, the candidate effects, the loop and its verdict (-> Diagnosis)."""
