"""Figures and the HTML reproduction report."""
