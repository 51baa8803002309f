//! The schemas and channels met so far: a record is checked against them before use (a
//! message on a channel no record defined, an id defined twice differently, is damage),
//! and messages are handed to the visitor with their channel's topic and schema.

use std::collections::HashMap;

use super::message::RawMessage;
use super::records::Record;
use super::{Channel, Fault, Reader, Schema};
use crate::error::BagError;

impl Reader<'_> {
    /// A record is consistent with the schemas and channels known (and those defined
    /// earlier in its chunk).
    pub(super) fn check(
        &self,
        r: &Record,
        chunk_schemas: &HashMap<u16, ()>,
        chunk_channels: &HashMap<u16, ()>,
    ) -> Result<(), Fault> {
        let bad = |m: String| Err(Fault::Record(m));
        match r {
            Record::Schema { id: 0, .. } => bad("a schema with id 0 (reserved for none)".into()),
            Record::Schema {
                id,
                name,
                encoding,
                data,
            } => match self.schemas.get(id) {
                Some(s)
                    if (s.name.as_str(), s.encoding.as_str(), s.data.as_slice())
                        != (*name, *encoding, *data) =>
                {
                    bad(format!(
                        "schema {id} is defined twice, differently (`{}` and `{name}`)",
                        s.name
                    ))
                }
                _ => Ok(()),
            },
            Record::Channel {
                id,
                schema,
                topic,
                encoding,
            } => {
                if *schema != 0
                    && !self.schemas.contains_key(schema)
                    && !chunk_schemas.contains_key(schema)
                {
                    return bad(format!("channel {id} (`{topic}`) names schema {schema}, which no earlier record defines"));
                }
                match self.channels.get(id) {
                    Some(c)
                        if (c.topic.as_str(), c.encoding.as_str(), c.schema)
                            != (*topic, *encoding, *schema) =>
                    {
                        bad(format!(
                            "channel {id} is defined twice, differently (`{}` and `{topic}`)",
                            c.topic
                        ))
                    }
                    _ => Ok(()),
                }
            }
            Record::Message { channel, .. } => {
                if self.channels.contains_key(channel) || chunk_channels.contains_key(channel) {
                    Ok(())
                } else {
                    bad(format!(
                        "a message on channel {channel}, which no earlier record defines"
                    ))
                }
            }
            Record::Other => Ok(()),
        }
    }

    /// Uses a checked record: schemas and channels are kept, messages visited.
    pub(super) fn apply(
        &mut self,
        r: Record,
        visit: &mut dyn FnMut(&RawMessage) -> Result<(), BagError>,
    ) -> Result<(), Fault> {
        match r {
            Record::Schema {
                id,
                name,
                encoding,
                data,
            } => {
                self.schemas.entry(id).or_insert_with(|| Schema {
                    name: name.to_string(),
                    encoding: encoding.to_string(),
                    data: data.to_vec(),
                });
            }
            Record::Channel {
                id,
                schema,
                topic,
                encoding,
            } => {
                self.channels.entry(id).or_insert_with(|| Channel {
                    topic: topic.to_string(),
                    encoding: encoding.to_string(),
                    schema,
                });
            }
            Record::Message {
                channel,
                log_time,
                data,
            } => {
                let Some(c) = self.channels.get(&channel) else {
                    return Err(Fault::Record(format!(
                        "a message on unknown channel {channel}"
                    )));
                };
                let schema = self.schemas.get(&c.schema);
                visit(&RawMessage {
                    topic: &c.topic,
                    type_name: schema.map_or("", |s| s.name.as_str()),
                    schema: schema.map(|s| (s.encoding.as_str(), s.data.as_slice())),
                    encoding: &c.encoding,
                    log_time,
                    data,
                })
                .map_err(Fault::Visit)?;
                self.outcome.messages += 1;
                self.last_log = Some(log_time);
            }
            Record::Other => {}
        }
        Ok(())
    }
}
