int helper() { return 2; } // HELPER_SEARCH
