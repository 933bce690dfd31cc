"""mrmp"""
