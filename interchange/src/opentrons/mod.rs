//! Opentrons: analysis JSON and Protocol Designer JSON (schema 8) read into one shape
//! ([`source`]), each command's fate ([`commands`]) and the run realised on our bench
//! ([`realise`]).

pub mod commands;
pub mod realise;
pub mod source;
