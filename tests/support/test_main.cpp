#define BOOST_TEST_MODULE paloverde
#include <boost/test/unit_test.hpp>
